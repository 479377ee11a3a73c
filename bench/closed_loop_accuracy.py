#!/usr/bin/python3
"""The closed loop's measured accuracy (issue #57's targets): three controllers on
rest_turned.yaml with an accuracy request, each run twice, measured (flex3rpr.Sim with the
request: the check stepped beside it) and unmeasured (accuracy.verify false), and the commands
the measured run applied replayed open loop on a converged reference (fixed-free links at
r = 8 with the static pair, exact kinematics, IDA at rtol 1e-10). Prints, per controller, the
measured error, the true error (the largest end-effector distance from the reference), their
ratio, and the CPU time of the measured and the unmeasured loop.

    /usr/bin/python3 bench/closed_loop_accuracy.py [--request 1e-6] [--periods 500]

Targets: measured at least a third of the true error; the measured loop at most 3 times the
unmeasured one's cost. Timing: process CPU time, one run each (repeat for spread).
"""
import argparse
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "src"))
sys.path.insert(0, os.path.join(ROOT, "examples", "python"))
import flex3rpr  # noqa: E402

SCENE = os.path.join(ROOT, "config", "scenes", "rest_turned.yaml")
REFERENCE = {"links.modes": 8, "links.static_correction": True,
             "effects.exact_kinematics": True, "solver.integrator": "ida",
             "solver.formulation": "minimal", "solver.rtol": 1e-10, "solver.atol": 1e-12}
RHO0 = 0.126  # rest_turned.yaml's strokes


MOVE = np.array([0.01, -0.005, 0.0])  # the strokes' change: the platform moves in x and y


def step_pd(state, k):
    target = RHO0 + (MOVE if k >= 20 else 0.0)
    u = np.zeros(6)
    u[:3] = 600.0 * (target - state.q[:3]) - 30.0 * state.v[:3]
    return u


def smooth_pd(state, k):
    s = min(1.0, max(0.0, (k - 20) / 200.0))
    target = RHO0 + MOVE * (3 * s ** 2 - 2 * s ** 3)
    u = np.zeros(6)
    u[:3] = 600.0 * (target - state.q[:3]) - 30.0 * state.v[:3]
    return u


def make_lqr(sim):
    try:
        import example_common as ex
    except ImportError:
        return None
    try:
        plant = sim.linearise()
        K, _, _ = ex.lqr(plant, sim.period)
    except Exception as e:  # scipy missing
        print("lqr: skipped (%s)" % e)
        return None
    n = plant["A"].shape[0] // 2
    x_target = np.zeros(2 * n)
    x_target[:3] = np.array([0.01, 0.0, 0.0])

    def lqr(state, k):
        return -K @ (ex.plant_state(state, plant) - x_target)
    return lqr


def loop(sim, controller, periods):
    state, applied = sim.state, []
    start = time.process_time()
    for k in range(periods):
        u = np.asarray(controller(state, k), dtype=float)
        applied.append(u)
        state = sim.step(u)
    return time.process_time() - start, applied


def true_error(measured_sim, applied):
    ref = flex3rpr.Sim(SCENE, overrides=REFERENCE, period=measured_sim.period)
    run = flex3rpr.Sim(SCENE, accuracy=measured_sim.accuracy["request"],
                       overrides={"accuracy.verify": False}, period=measured_sim.period)
    worst = 0.0
    for u in applied:
        a, b = run.step(u), ref.step(u)
        worst = max(worst, float(np.hypot(a.x_p - b.x_p, a.y_p - b.y_p)))
    return worst


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--request", type=float, default=1e-6)
    p.add_argument("--periods", type=int, default=500)
    args = p.parse_args()
    probe = flex3rpr.Sim(SCENE, accuracy=args.request)
    print("scene %s, request %g m, %d periods of 1 ms; the knob: %s" % (
        os.path.basename(SCENE), args.request, args.periods, probe.accuracy["summary"].split("\n")[0]))
    controllers = [("step PD", step_pd), ("smooth PD", smooth_pd)]
    lqr = make_lqr(flex3rpr.Sim(SCENE))
    if lqr:
        controllers.append(("LQR", lqr))
    print("| controller | measured (m) | true (m) | measured / true | request met (measured) | "
          "CPU measured (s) | CPU unmeasured (s) | ratio |")
    print("|---|---|---|---|---|---|---|---|")
    for name, controller in controllers:
        measured = flex3rpr.Sim(SCENE, accuracy=args.request)
        plain = flex3rpr.Sim(SCENE, accuracy=args.request, overrides={"accuracy.verify": False})
        cpu_m, applied = loop(measured, controller, args.periods)
        cpu_u, _ = loop(plain, controller, args.periods)
        truth = true_error(measured, applied)
        m = measured.measured_error_m
        print("| %s | %.3g | %.3g | %.2f | %s | %.3f | %.3f | %.2f |" % (
            name, m, truth, m / truth if truth > 0 else float("nan"), measured.request_met,
            cpu_m, cpu_u, cpu_m / cpu_u))


if __name__ == "__main__":
    main()

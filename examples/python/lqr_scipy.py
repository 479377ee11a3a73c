#!/usr/bin/python3
"""An LQR designed with scipy on Sim.linearise(), then checked on the nonlinear model: the 1 cm
move of rest.yaml's platform from a controllable start, at 1 kHz.

The plant x' = A x + B u (x = (z - z0, z'), z = pose and modal coordinates; u = three leg forces
and three cylinder torques) is discretised with a zero-order hold at the period, and the discrete
Riccati equation gives K for Bryson's weights on the pose, its rate and the tip deflections. The
same u = -K (x - x*) then drives the linear model and the nonlinear one. Writes lqr.png and
lqr.json (the final errors and tip deflections of both) to --out.
"""
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import example_common as ex  # noqa: E402
import flex3rpr  # noqa: E402


def main():
    args = ex.arguments(__doc__)
    periods = 150 if args.quick else 500
    sim = flex3rpr.Sim(ex.SCENE, overrides=ex.START_FIELDS)
    plant = sim.linearise()
    K, Ad, Bd = ex.lqr(plant, sim.period)
    n = plant["A"].shape[0] // 2
    x_target = np.zeros(2 * n)
    x_target[:3] = ex.TARGET - plant["x0"][:3]
    tips_row = plant["C"][9:12]
    x_lin = np.zeros(2 * n)
    lin, nonlin = [], []
    state = sim.state
    for k in range(periods):
        x = ex.plant_state(state, plant)
        state = sim.step(-K @ (x - x_target))
        nonlin.append([state.t, state.x_p, *state.tip_deflection])
        x_lin = Ad @ x_lin + Bd @ (-K @ (x_lin - x_target))
        lin.append([(k + 1) * sim.period, plant["x0"][0] + x_lin[0], *(tips_row @ x_lin)])
    lin, nonlin = np.array(lin), np.array(nonlin)
    result = {"periods": periods,
              "final_error_linear_m": float(abs(lin[-1, 1] - ex.TARGET[0])),
              "final_error_nonlinear_m": float(abs(nonlin[-1, 1] - ex.TARGET[0])),
              "max_tip_linear_m": float(np.max(np.abs(lin[:, 2:]))),
              "max_tip_nonlinear_m": float(np.max(np.abs(nonlin[:, 2:]))),
              "largest_path_difference_m": float(np.max(np.abs(lin[:, 1] - nonlin[:, 1])))}
    with open(os.path.join(args.out, "lqr.json"), "w") as f:
        json.dump(result, f, indent=1)
    fig, (a, b) = plt.subplots(2, 1, figsize=(6, 5), sharex=True)
    a.plot(lin[:, 0], 1e3 * lin[:, 1], label="linear model")
    a.plot(nonlin[:, 0], 1e3 * nonlin[:, 1], "--", label="nonlinear model")
    a.set_ylabel("x_p (mm)"), a.legend()
    b.plot(lin[:, 0], 1e6 * lin[:, 2:], lw=0.8)
    b.plot(nonlin[:, 0], 1e6 * nonlin[:, 2:], "--", lw=0.8)
    b.set_ylabel("tip deflection (um)"), b.set_xlabel("t (s)")
    fig.savefig(os.path.join(args.out, "lqr.png"), dpi=90, bbox_inches="tight")
    print("lqr_scipy: final x error %.3g m (linear %.3g m); largest tip deflection %.3g m "
          "(linear %.3g m); paths apart by at most %.3g m"
          % (result["final_error_nonlinear_m"], result["final_error_linear_m"],
             result["max_tip_nonlinear_m"], result["max_tip_linear_m"],
             result["largest_path_difference_m"]))


if __name__ == "__main__":
    main()

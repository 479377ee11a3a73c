#!/usr/bin/python3
"""What the Python module costs: a 1 kHz PD in Python against the CLI on the same commands,
how busy batched rollouts keep the cores, and a 200-point parameter study against the
process-per-run sweep (nodes/sweep) on the same runs. Prints a Markdown report; timings are
CPU and wall times of this machine, never asserted by a test.

  source build/ws/devel/setup.bash; bench/python_module.py [--quick] [--out FILE.md]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
# flex3rpr_tools, the module the scripts share, lives in nodes/ beside the rosrun tools.
sys.path.insert(0, os.path.join(ROOT, "nodes"))
import flex3rpr_tools as T  # noqa: E402

flex3rpr = None  # the built module, imported in main() once the arguments are read (--help needs no build)
SCENE = os.path.join(ROOT, "config", "scenes", "rest.yaml")
START = {"initial.platform_pose": [0.0, 0.0, 0.3]}  # away from the singular home


def pd_loop(periods):
    """A PD on the legs in Python and numpy, 1 kHz: periods a CPU second, and its commands."""
    sim = flex3rpr.Sim(SCENE, overrides=START)
    target = flex3rpr.Sim(SCENE, overrides=START)
    target.set_state([0.01, 0.0, 0.3])
    reference = target.state.q[:3].copy()
    held = np.zeros(sim.nq)
    commands = np.zeros((periods, 3))
    nq = sim.nq
    row = sim.state.vector
    start = time.process_time()
    for k in range(periods):
        held[:3] = 2000.0 * (reference - row[1:4]) - 40.0 * row[4 + nq:7 + nq]
        commands[k] = held[:3]
        row = sim.step_forces(held)
    cpu = time.process_time() - start
    return periods / cpu, commands, row.copy(), sim.columns


def cli_hold_table(commands, workdir):
    """The same commands as 1 kHz hold tables in a scene, run by the CLI: periods a CPU second
    (its own run.cpu_time_s) and the final row of its CSV."""
    periods = len(commands)
    times = [k * 1e-3 for k in range(periods + 1)]
    with open(SCENE) as f:
        text = f.read()
    tables = "inputs:\n" + "".join(
        "  rho_%d: {table: {time: %s, value: %s, interpolation: hold}}\n"
        % (i + 1, json.dumps(times), json.dumps(commands[:, i].tolist() + [0.0]))
        for i in range(3))
    scene = os.path.join(workdir, "pd_commands.yaml")
    with open(scene, "w") as f:
        f.write(text + "\n" + tables)
    out = os.path.join(workdir, "pd.csv")
    summary, p = T.run_sim(T.find_binary(), scene, "--out", out, "--set", "run.duration=%r" % (periods * 1e-3),
                           "--set", "run.output_step=0.001", "--set", "initial.platform_pose=[0.0, 0.0, 0.3]")
    if p.returncode != 0 or not summary:
        raise RuntimeError("flex3rpr_sim: " + T.error_message(summary, p))
    cpu = summary["run"]["cpu_time_s"]
    with open(out) as f:
        last = list(csv.reader(f))[-1]
    assert abs(float(last[0]) - periods * 1e-3) < 1e-12, "the CLI ran %s s" % last[0]
    return periods / cpu, np.array([float(x) for x in last])


def replay(commands):
    """The PD's commands replayed open loop from Python: the loop without the controller."""
    sim = flex3rpr.Sim(SCENE, overrides=START)
    held = np.zeros(sim.nq)
    start = time.process_time()
    for c in commands:
        held[:3] = c
        sim.step_forces(held)
    return len(commands) / (time.process_time() - start)


def utilisation(n, periods):
    """Batched rollouts: (wall s, CPU s of every process, cores busy as a share)."""
    gains = np.linspace(500.0, 5000.0, n)

    def policy(state, k, run):
        return [gains[run] * (0.125 - state.rho_1), 0.0, 0.0, 0.0, 0.0, 0.0]

    before, wall = os.times(), time.perf_counter()
    flex3rpr.rollouts(SCENE, policy=policy, n=n, periods=periods, overrides=START)
    wall = time.perf_counter() - wall
    after = os.times()
    cpu = sum(getattr(after, f) - getattr(before, f)
              for f in ("user", "system", "children_user", "children_system"))
    return wall, cpu, cpu / (wall * os.cpu_count())


def parameter_study(points, workdir):
    """200 Young's moduli on paper simulation 1 cut to 0.05 s: the sweep (a process and a CSV a
    run) against flex3rpr.study in one process a core; wall times and the largest difference
    of the final x_p between them."""
    moduli = np.linspace(60e9, 90e9, points)
    spec = os.path.join(workdir, "study.yaml")
    with open(spec, "w") as f:
        f.write("base: %s\nparameters:\n  run.duration: [0.05]\n"
                "  link.youngs_modulus: %s\nmetrics: [final_x]\ntimeout: 600\n"
                % (os.path.join(ROOT, "config", "scenes", "paper_sim1.yaml"),
                   json.dumps(moduli.tolist())))
    out = os.path.join(workdir, "sweep")
    wall = time.perf_counter()
    subprocess.run([sys.executable, os.path.join(ROOT, "nodes", "sweep"), spec, "--out", out],
                   check=True, stdout=subprocess.DEVNULL)
    sweep_wall = time.perf_counter() - wall
    with open(os.path.join(out, "results.csv")) as f:
        rows = sorted(csv.DictReader(f), key=lambda r: int(r["id"].split("-")[0]))
    swept = [float(r["final_x"]) for r in rows]
    wall = time.perf_counter()
    results = flex3rpr.study(os.path.join(ROOT, "config", "scenes", "paper_sim1.yaml"),
                             [{"link.youngs_modulus": float(e), "run.duration": 0.05}
                              for e in moduli], columns=["x_p"])
    study_wall = time.perf_counter() - wall
    apart = max(abs(r["x_p"][-1] - x) for r, x in zip(results, swept))
    return sweep_wall, study_wall, apart


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="shorter runs, for a smoke test")
    parser.add_argument("--out", help="also write the report to this file")
    args = parser.parse_args()
    global flex3rpr
    import flex3rpr  # noqa: F811  (source build/ws/devel/setup.bash first)
    periods = 200 if args.quick else 1000
    lines = ["| measurement | value |", "|---|---|"]
    with tempfile.TemporaryDirectory() as work:
        rate, commands, final, columns = pd_loop(periods)
        cli_rate, cli_final = cli_hold_table(commands, work)
        replay_rate = replay(commands)
        states = columns.index("lambda_1x")  # t, q, v, tips; the multipliers at the last
        # instant take the force's one-sided limit there, which a table and a held command
        # give differently
        same = np.max(np.abs(final[:states] - cli_final[:states]) /
                      np.maximum(1.0, np.abs(cli_final[:states])))
        lines += ["| PD in Python, 1 kHz, rest.yaml from phi = 0.3 | %.0f periods per CPU s |"
                  % rate,
                  "| the same commands replayed from Python (no controller) | %.0f periods per "
                  "CPU s |" % replay_rate,
                  "| the same commands as 1 kHz hold tables, flex3rpr_sim | %.0f periods per CPU "
                  "s |" % cli_rate,
                  "| PD in Python / CLI | %.2f |" % (rate / cli_rate),
                  "| final state (t, q, v, tips), Python against the CLI's CSV | %.1e relative |" % same]
        n = 8 if args.quick else 40
        wall, cpu, busy = utilisation(n, 100 if args.quick else 500)
        lines += ["| %d rollouts of a PD, %d cores | %.2f s wall, %.2f CPU s, cores %.0f %% "
                  "busy |" % (n, os.cpu_count(), wall, cpu, 100 * busy)]
        points = 20 if args.quick else 200
        sweep_wall, study_wall, apart = parameter_study(points, work)
        lines += ["| %d-point study, nodes/sweep (a process a run) | %.1f s wall |"
                  % (points, sweep_wall),
                  "| the same with flex3rpr.study | %.1f s wall (%.1fx faster); final x_p apart "
                  "by %.1e m |" % (study_wall, sweep_wall / study_wall, apart)]
    report = "\n".join(lines)
    print(report)
    if args.out:
        with open(args.out, "w") as f:
            f.write(report + "\n")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Markdown tables for the README: every shipped scene (state dimension, steps, residual
evaluations, CPU time per simulated second, real-time factor), and the cost of each effect
measured alone against paper simulation 3 (fixed-free) without it. Long scenes are shortened.

usage: scene_table.py FLEX3RPR_SIM SCENES_DIR"""
import argparse
import os
import sys
import tempfile

# flex3rpr_tools, the module the scripts share, lives in nodes/ beside the rosrun tools.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.realpath(__file__))), "nodes"))
import flex3rpr_tools as T  # noqa: E402

SHORTEN = {"free_vibration_long.yaml": 2.0, "stiff_high_modes.yaml": 0.01}


def run(sim, scene, *extra):
    """The run's numbers from the CLI's JSON summary; "wall" is its integration time (wall clock)."""
    summary, p = T.run_sim(sim, scene, *extra)
    if p.returncode != 0:
        raise SystemExit(f"scene_table.py: {scene}: {T.error_message(summary, p)}")
    r = summary["run"]
    return {"dim": summary["settings"]["state_dimension"], "steps": r["steps"], "evals": r["residual_evals"],
            "t": r["simulated_time_s"], "wall": r["integration_wall_time_s"]}


def main(sim, scenes):
    print("| scene | state dimension | simulated (s) | steps | residual evals | integration wall s per simulated s | real-time factor (wall) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name in sorted(os.listdir(scenes)):
        if not name.endswith(".yaml"):
            continue
        extra = ["--duration", str(SHORTEN[name])] if name in SHORTEN else []
        r = run(sim, os.path.join(scenes, name), *extra)
        per = r["wall"] / r["t"]
        print(f"| {name} | {r['dim']} | {r['t']:g} | {r['steps']} | {r['evals']} | {per:.3g} | {1 / per:.3g} |")
    base = open(os.path.join(scenes, "paper_sim3_fixed_free.yaml")).read()
    effects = {
        "exact_kinematics": "effects: {exact_kinematics: true}\n",
        "gravity (base tilted 10 degrees)": "effects: {gravity: [0.0, -1.7035, -9.6610]}\n",
        "payload 0.1 kg": "effects: {payload: {mass: 0.1, inertia: 1.0e-5}}\n",
        "joint_friction": "effects: {joint_friction: {prismatic: [0.5, 0.5, 0.5], revolute: [0.001, 0.001, 0.001]}}\n",
        "actuator_lag 5 ms": "effects: {actuator_lag: {time_constant: 0.005}}\n",
        "end_stops (root functions; no impact in this run)": "effects: {end_stops: {min: -0.1, max: 0.3, restitution: 0.5}}\n",
        "damping_ratio 0.01": None,
    }
    print()
    print("| effect (alone, on paper_sim3_fixed_free) | steps | residual evals | wall time ratio to the scene without it |")
    print("|---|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "base.yaml")
        open(path, "w").write(base)
        ref = run(sim, path)
        for label, text in effects.items():
            body = base + text if text else base.replace("links: {model: fixed_free, modes: 3}",
                                                         "links: {model: fixed_free, modes: 3, damping_ratio: 0.01}")
            p = os.path.join(tmp, "effect.yaml")
            open(p, "w").write(body)
            r = run(sim, p)
            print(f"| {label} | {r['steps']} | {r['evals']} | {r['wall'] / ref['wall']:.2f} |")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("sim", metavar="FLEX3RPR_SIM", help="the CLI")
    ap.add_argument("scenes", metavar="SCENES_DIR", help="the scenes, e.g. config/scenes")
    args = ap.parse_args()
    main(args.sim, args.scenes)

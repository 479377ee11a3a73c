#!/usr/bin/python3
"""Writes src/core/accuracy/solver_table.def, the accuracy knob's measured solver relations, from the
work-precision benchmark's build/bench/tolerance.csv (bench/work_precision calls it after a full run).

For each kind of scene (flexible links; all links rigid; held commands, as the node gives them),
each of our own methods measured on every benchmark scene of that kind and each tolerance
measured on all of them: the largest end-effector error over those scenes (m) and the median
over them of the CPU time relative to that scene's minimal IDA at rtol 1e-6.
"""
import argparse
import collections
import csv
import os
import statistics
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "src/core/accuracy/solver_table.def")

# benchmark scene label -> kind
KINDS = {"rigid (sim1 forcing)": "rigid", "closed loop (1 kHz hold)": "commanded"}
# benchmark method label -> (formulation, integrator, Butcher table); methods not listed (peers,
# Debian's SUNDIALS, difference quotients, dense LU, BDF order <= 2) are not the knob's to pick
METHODS = {
    "minimal, IDA, analytic": ("F3R_FORMULATION_MINIMAL", "F3R_INTEGRATOR_IDA", ""),
    "dae, IDA, analytic": ("F3R_FORMULATION_DAE", "F3R_INTEGRATOR_IDA", ""),
    "minimal, ERK Fehlberg 7(8)": ("F3R_FORMULATION_MINIMAL", "F3R_INTEGRATOR_ERK", ""),
    "minimal, ERK Dormand-Prince 5(4)": ("F3R_FORMULATION_MINIMAL", "F3R_INTEGRATOR_ERK", "ARKODE_DORMAND_PRINCE_7_4_5"),
    "minimal, ERK DOP853 8(5)": ("F3R_FORMULATION_MINIMAL", "F3R_INTEGRATOR_ERK", "dormand_prince_8_5"),
    "minimal, ERK Verner 8(7)": ("F3R_FORMULATION_MINIMAL", "F3R_INTEGRATOR_ERK", "verner_8_7"),
    "minimal, ERK Verner 9(8)": ("F3R_FORMULATION_MINIMAL", "F3R_INTEGRATOR_ERK", "verner_9_8"),
    "minimal, DIRK ESDIRK Kvaerno 5(4)": ("F3R_FORMULATION_MINIMAL", "F3R_INTEGRATOR_DIRK", ""),
}
BASELINE = ("minimal, IDA, analytic", 1e-6)


def relations(rows):
    kind_scenes = collections.defaultdict(set)
    for r in rows:
        kind_scenes[KINDS.get(r["scene"], "flexible")].add(r["scene"])
    baseline = {r["scene"]: float(r["cpu_s"]) for r in rows
                if r["method"] == BASELINE[0] and abs(float(r["rtol"]) / BASELINE[1] - 1) < 1e-6}
    out = []
    for kind, scenes in sorted(kind_scenes.items()):
        for method, spec in METHODS.items():
            by_rtol = collections.defaultdict(dict)
            for r in rows:
                if r["method"] == method and r["scene"] in scenes and r["error_m"] not in ("", "nan"):
                    by_rtol[float(r["rtol"])][r["scene"]] = r
            for rtol, per_scene in sorted(by_rtol.items(), reverse=True):
                if set(per_scene) != scenes or any(s not in baseline for s in scenes):
                    continue
                error = max(float(r["error_m"]) for r in per_scene.values())
                cost = statistics.median(max(float(r["cpu_s"]), 1e-6) / max(baseline[s], 1e-6)
                                         for s, r in per_scene.items())
                out.append((kind, spec, rtol, error, cost, len(scenes)))
    return out


def write(rels, stamp):
    """The rows as solver_table.c's data: one F3R_RELATION(...) per line."""
    lines = ["/* Written by bench/solver_table.py from the work-precision benchmark (bench/work_precision): do not",
             " * edit. Data for solver_table.c: error is the largest end-effector error (m) over the benchmark",
             " * scenes of the kind, cost the median over them of CPU time / CPU time of minimal IDA at rtol 1e-6.",
             " * F3R_RELATION(kind, formulation, integrator, table, rtol, atol, error, cost, scenes) */",
             f'F3R_RELATIONS_SOURCE("{stamp}")']
    for kind, (form, integ, table), rtol, error, cost, n in rels:
        atol = rtol * 1e-2  # bench/work_precision's tol_args
        lines.append(f'F3R_RELATION("{kind}", {form}, {integ}, "{table}", {rtol:.6g}, {atol:.6g}, {error:.3g}, {cost:.3g}, {n})')
    with open(OUT, "w") as f:
        f.write("\n".join(lines) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("tolerance_csv", nargs="?", default=os.path.join(ROOT, "build/bench/tolerance.csv"),
                    help="the benchmark's tolerance sweep (default: %(default)s)")
    ap.add_argument("--stamp", default="unstamped", help="machine, date and commit of the measurement")
    args = ap.parse_args()
    rows = list(csv.DictReader(open(args.tolerance_csv)))
    rels = relations(rows)
    if not rels:
        sys.exit(f"solver_table: no complete relation in {args.tolerance_csv}")
    write(rels, args.stamp.replace('"', "'"))
    print(f"solver_table: {len(rels)} relations -> {os.path.relpath(OUT, ROOT)}")

if __name__ == "__main__":
    main()

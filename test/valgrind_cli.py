#!/usr/bin/python3
"""valgrind memcheck on the CLI: no invalid access, no use of uninitialised values, no leak.
Runs the first 20 ms of a paper scene with both formulations; writes one JUnit case per run."""
import argparse
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "nodes"))
import flex3rpr_tools  # noqa: E402  (scripts/: JUnit)

ap = argparse.ArgumentParser()
ap.add_argument("--junit", required=True)
ap.add_argument("--valgrind", required=True)
ap.add_argument("--cli", required=True)
ap.add_argument("--scene", required=True)
args = ap.parse_args()
cases = []
for formulation in ("minimal", "dae"):
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [args.valgrind, "--error-exitcode=99", "--leak-check=full", "--errors-for-leak-kinds=definite,indirect",
               args.cli, args.scene, "--formulation", formulation, "--duration", "0.02", "--out", tmp + "/run.csv"]
        p = subprocess.run(cmd, capture_output=True, text=True)
    summary = [l for l in p.stderr.splitlines() if "ERROR SUMMARY" in l or "definitely lost" in l]
    print(f"{formulation}: exit {p.returncode}; " + "; ".join(s.split("==", 2)[-1].strip() for s in summary))
    failure = None if p.returncode == 0 else f"valgrind exit {p.returncode}\n{p.stderr[-4000:]}"
    cases.append(("valgrind", f"cli_{formulation}", failure))
sys.exit(1 if flex3rpr_tools.write_junit(args.junit, "valgrind_cli", cases) else 0)

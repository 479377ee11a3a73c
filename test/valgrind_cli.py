#!/usr/bin/python3
"""valgrind memcheck on the CLI: no invalid access, no use of uninitialised values, no leak.
Runs the first 20 ms of a paper scene with both formulations; writes one JUnit case per run."""
import argparse
import subprocess
import sys
import tempfile
from xml.sax.saxutils import escape

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
    failure = "" if p.returncode == 0 else f'<failure message="valgrind exit {p.returncode}">{escape(p.stderr[-4000:])}</failure>'
    cases.append(f'<testcase classname="valgrind" name="cli_{formulation}">{failure}</testcase>')
with open(args.junit, "w") as f:
    failures = sum("<failure" in c for c in cases)
    f.write(f'<testsuite name="valgrind_cli" tests="{len(cases)}" errors="0" failures="{failures}" skipped="0">'
            f'{"".join(cases)}</testsuite>\n')
sys.exit(0 if all("failure" not in c for c in cases) else 1)

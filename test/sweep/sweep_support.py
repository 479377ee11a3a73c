"""What the sweep tests share: the 24-run spec, running nodes/sweep, reading results, JUnit."""
import argparse
import csv
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "nodes"))
import flex3rpr_tools  # noqa: E402  (scripts/: JUnit)
SWEEP = os.path.join(ROOT, "nodes", "sweep")
TIMING_COLUMNS = {"cpu_time_s", "wall_time_s", "host"}

# 4 diameters x 2 boundary models x 3 random platform masses, 0.02 s of paper simulation 3 each
SPEC24 = """\
base: {root}/config/scenes/paper_sim3_fixed_free.yaml
args: [--rtol, 1.0e-6, --duration, {duration}, --output-step, 1.0e-3]
parameters:
  link.diameter: {{range: [0.008, 0.012, 4]}}
  links.model: [fixed_free, fixed_pinned]
  platform.mass: {{random: normal, mean: 0.2, sd: 0.01, count: 3}}
seed: 7
reference: {{links.modes: 6}}
timeout: 3600
keep_runs: true
slurm: {{array_size: 6, time: "00:30:00", mem: 500M}}
"""


def write_spec(directory, name, text):
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def sweep(*args, sim, timeout=3600, **kwargs):
    """Runs nodes/sweep to its end: (exit code, stderr)."""
    env = dict(os.environ, F3R_SIM=sim)
    p = subprocess.run(["/usr/bin/python3", SWEEP, *args], capture_output=True, text=True, env=env,
                       timeout=timeout, **kwargs)
    return p.returncode, p.stderr


def read_results(out_dir):
    with open(os.path.join(out_dir, "results.csv")) as f:
        return list(csv.DictReader(f))


def without_timing(rows):
    return [{k: v for k, v in r.items() if k not in TIMING_COLUMNS} for r in rows]


def wait_for(predicate, timeout=1800, step=0.05):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(step)
    return predicate()


def run_junit(test_case_classes, junit_path, suite_name):
    """Runs the cases, prints unittest's report, writes JUnit XML; exit code 0 when all pass."""
    return flex3rpr_tools.run_unittest(test_case_classes, junit_path, suite_name)


def parse_args(prefix):
    """The sweep tests' command line: --sim FLEX3RPR_SIM [--junit FILE] [--work DIR]."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--sim", required=True)
    ap.add_argument("--junit")
    ap.add_argument("--work")
    args = ap.parse_args()
    args.work = os.path.abspath(args.work or tempfile.mkdtemp(prefix=prefix))
    return args

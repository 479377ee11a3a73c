#!/usr/bin/python3
"""Parameter sweeps (nodes/sweep) on the local and ssh engines: real GNU parallel, the real CLI.

usage: test_sweep.py --sim FLEX3RPR_SIM [--junit FILE] [--work DIR]

- a 24-run grid gives 24 rows in expansion order with deterministic ids, and every metric agrees
  with the run's own CSV (read here, independently of the runner);
- the ssh engine (GNU parallel --sshloginfile, with parallel's ':' for this host) gives the same
  rows as the local engine, apart from the timing columns;
- a point driven into a leg collapse and one past the spec's timeout are rows with their errors,
  and the sweep completes; on a terminal the progress bar shows done, failed, remaining and ETA;
- an interrupted sweep, resumed, runs only the points it had not finished;
- a bad spec stops before any run, naming the file and the field.
"""
import json
import math
import os
import pty
import shutil
import signal
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sweep_support as S  # noqa: E402

ARGS = None


def csv_path(out_dir, run_id):
    import csv
    with open(os.path.join(out_dir, "runs", run_id + ".csv")) as f:
        return list(csv.DictReader(f))


class LocalAndSsh(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = ARGS.work
        cls.spec = S.write_spec(cls.work, "grid24.yaml", S.SPEC24.format(root=S.ROOT, duration=0.02))
        cls.local = os.path.join(cls.work, "local")
        shutil.rmtree(cls.local, ignore_errors=True)
        cls.rc, cls.log = S.sweep(cls.spec, "--out", cls.local, sim=ARGS.sim)
        print(cls.log)

    def test_a_grid_has_one_row_per_point_in_order_with_deterministic_ids(self):
        self.assertEqual(self.rc, 0, self.log)
        rows = S.read_results(self.local)
        self.assertEqual(len(rows), 24)
        self.assertTrue(all(r["status"] == "ok" for r in rows), [r["error"] for r in rows])
        rc, out = subprocess.getstatusoutput(f"F3R_SIM={ARGS.sim} /usr/bin/python3 {S.SWEEP} {self.spec} --dry-run 2>/dev/null")
        self.assertEqual(rc, 0, out)
        dry = [line.split()[0] for line in out.splitlines()]
        self.assertEqual([r["id"] for r in rows], dry, "ids and order as the expansion gives them")
        self.assertEqual([int(r["id"][:5]) for r in rows], list(range(24)))
        diameters = sorted({float(r["link.diameter"]) for r in rows})
        self.assertEqual(len(diameters), 4)
        # a range's values are written at 12 significant digits (0.009, not 0.009000000000000001)
        for got, want in zip(diameters, [0.008, 0.008 + 0.004 / 3, 0.008 + 0.008 / 3, 0.012]):
            self.assertEqual(got, float(f"{want:.12g}"))
        self.assertEqual({r["links.model"] for r in rows}, {"fixed_free", "fixed_pinned"})
        masses = {r["platform.mass"] for r in rows}
        self.assertEqual(len(masses), 3, "three draws, each combined with every other value")
        self.assertTrue(all(0.15 < float(m) < 0.25 for m in masses), masses)
        # the grid: every combination exactly once
        combos = {(r["link.diameter"], r["links.model"], r["platform.mass"]) for r in rows}
        self.assertEqual(len(combos), 24)

    def test_b_metrics_agree_with_each_runs_own_csv(self):
        rows = S.read_results(self.local)
        reference = {round(float(r["t"]), 9): (float(r["x_p"]), float(r["y_p"]))
                     for r in csv_path(self.local, "reference")}
        for row in rows:
            run = csv_path(self.local, row["id"])
            tip = max(abs(float(r[f"w_tip_{i}"])) for r in run for i in (1, 2, 3))
            self.assertAlmostEqual(float(row["tip_deflection_max"]), tip, delta=1e-6 * tip + 1e-15, msg=row["id"])
            if row["links.model"] == "fixed_pinned":
                self.assertEqual(tip, 0.0)
                self.assertGreater(float(row["deflection_max"]), 0.0, "a pinned beam bends between its ends")
            else:
                self.assertGreater(tip, 0.0)
                self.assertGreaterEqual(float(row["deflection_max"]), float(row["tip_deflection_max"]))
            d = [math.hypot(float(r["x_p"]) - reference[round(float(r["t"]), 9)][0],
                            float(r["y_p"]) - reference[round(float(r["t"]), 9)][1]) for r in run]
            self.assertEqual(len(d), 21)
            self.assertAlmostEqual(float(row["ee_max_deviation"]), max(d), delta=1e-12)
            self.assertAlmostEqual(float(row["ee_rms_deviation"]), math.sqrt(sum(x * x for x in d) / len(d)),
                                   delta=1e-12)
            self.assertAlmostEqual(float(row["final_x"]), float(run[-1]["x_p"]), delta=1e-9)
            self.assertGreater(int(row["steps"]), 0)
            self.assertGreater(int(row["residual_evals"]), int(row["steps"]) - 1)
            self.assertLess(float(row["energy_balance_relative"]), 1e-3)
        self.assertGreater(max(float(r["ee_max_deviation"]) for r in rows), 0.0)

    def test_c_the_ssh_engine_gives_the_same_rows(self):
        hosts = os.path.join(self.work, "hosts.txt")
        with open(hosts, "w") as f:
            f.write(":\n")  # GNU parallel's name for this host, reached without ssh
        out = os.path.join(self.work, "ssh")
        shutil.rmtree(out, ignore_errors=True)
        rc, log = S.sweep(self.spec, "--out", out, "--engine", "ssh", "--sshloginfile", hosts, sim=ARGS.sim)
        self.assertEqual(rc, 0, log)
        self.assertIn("(ssh)", log)
        self.assertEqual(S.without_timing(S.read_results(out)), S.without_timing(S.read_results(self.local)))

    def test_d_a_rerun_runs_nothing(self):
        rc, log = S.sweep(self.spec, "--out", self.local, sim=ARGS.sim)
        self.assertEqual(rc, 0, log)
        self.assertIn("24 already in the results, 0 to run", log)


class Faults(unittest.TestCase):
    def test_a_collapse_and_timeout_are_rows_and_the_sweep_completes(self):
        spec = S.write_spec(ARGS.work, "faults.yaml", f"""\
base: {S.ROOT}/config/scenes/paper_sim3_fixed_free.yaml
args: [--rtol, 1.0e-6]
parameters:
  inputs.rho_1.offset: [-50.0, -1000.0, -50.0]
  inputs.rho_1.amplitude: [50.0, 0.0, 50.0]
  run.duration: [0.02, 0.02, 10000.0]
  run.output_step: [1.0e-3, 1.0e-3, 1.0]
combine: zip
timeout: 4
""")
        # The third point drifts into a leg collapse at t = 180.75 s, 16.8 s of CPU time here (with
        # a 20 s timeout, a faster core ended it there, as 'failed'): 4 s leaves it four times that
        # margin, while the first two take milliseconds.
        out = os.path.join(ARGS.work, "faults")
        shutil.rmtree(out, ignore_errors=True)
        # on a terminal: the progress bar
        master, slave = pty.openpty()
        env = dict(os.environ, F3R_SIM=ARGS.sim)
        p = subprocess.Popen(["/usr/bin/python3", S.SWEEP, spec, "--out", out], stdin=slave, stdout=slave,
                             stderr=slave, env=env, close_fds=True)
        os.close(slave)
        chunks = []
        while True:
            try:
                data = os.read(master, 65536)
            except OSError:
                break
            if not data:
                break
            chunks.append(data)
        rc = p.wait(timeout=3600)
        os.close(master)
        text = b"".join(chunks).decode(errors="replace")
        self.assertEqual(rc, 0, text)
        rows = S.read_results(out)
        self.assertEqual([r["status"] for r in rows], ["ok", "failed", "timeout"], text)
        self.assertIn("leg 1 collapsed", rows[1]["error"])
        self.assertIn("timeout of 4 s", rows[2]["error"])
        self.assertTrue(os.path.exists(os.path.join(out, "logs", rows[1]["id"] + ".log")))
        self.assertRegex(text, r"\r\[[#.]{30}\] \d/3 done, \d failed, \d remaining, \d+ s, ETA ")
        self.assertIn("3 of 3 runs in the results (1 ok, 1 failed, 1 timeout)", text)
        # failures are results: resuming skips them, --retry-failed runs them again
        rc, log = S.sweep(spec, "--out", out, sim=ARGS.sim)
        self.assertIn("3 already in the results, 0 to run", log)

    def test_b_an_interrupted_sweep_resumes_with_the_missing_points_only(self):
        spec = S.write_spec(ARGS.work, "resume.yaml", S.SPEC24.format(root=S.ROOT, duration=0.2))
        out = os.path.join(ARGS.work, "resume")
        shutil.rmtree(out, ignore_errors=True)
        rows_dir = os.path.join(out, "rows")
        env = dict(os.environ, F3R_SIM=ARGS.sim)
        p = subprocess.Popen(["/usr/bin/python3", S.SWEEP, spec, "--out", out, "--jobs", "1"], env=env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)

        def done():
            return [n for n in os.listdir(rows_dir) if n.endswith(".json") and n != "reference.json"] \
                if os.path.isdir(rows_dir) else []

        self.assertTrue(S.wait_for(lambda: len(done()) >= 3 or p.poll() is not None))
        os.killpg(p.pid, signal.SIGTERM)
        p.communicate(timeout=600)
        before = {n: os.stat(os.path.join(rows_dir, n)).st_mtime_ns for n in done()}
        self.assertGreaterEqual(len(before), 3)
        self.assertLess(len(before), 24, "stopped before the end (runs of 0.2 s, one at a time)")
        rc, log = S.sweep(spec, "--out", out, sim=ARGS.sim)
        self.assertEqual(rc, 0, log)
        self.assertIn(f"{len(before)} already in the results, {24 - len(before)} to run", log)
        rows = S.read_results(out)
        self.assertEqual(len(rows), 24)
        self.assertTrue(all(r["status"] == "ok" for r in rows), [r["error"] for r in rows])
        for name, mtime in before.items():
            self.assertEqual(os.stat(os.path.join(rows_dir, name)).st_mtime_ns, mtime, f"{name} ran again")

    def test_c_a_bad_spec_stops_before_any_run_naming_file_and_field(self):
        cases = {
            "parameters:\n  link.diameter: {range: [0.01, 0.02, 0]}\n": "parameters.link.diameter: range",
            "parameters:\n  links.modes: [0, 3]\n": "parameters.links.modes: --set links.modes=0: links[0].modes: 0 is out of range 1..20",
            "parameters:\n  link.diameter: [0.01]\nmetrics: [tip]\n": "metrics: 'tip' is not one of",
            "parameters:\n  link.diameter: [0.01]\ncombine: cross\n": "combine: 'cross' is not one of grid, zip",
            "parameters:\n  link.diameter: [0.01, 0.02]\n  links.modes: [2]\ncombine: zip\n": "combine: zip needs the same number",
            "parameters:\n  link.diameter: [0.01]\ntimeout: -1\n": "timeout: -1 is out of range",
            "parameters:\n  link.diameter: [0.01]\nslurm: {array: 3}\n": "slurm.array: unknown key",
        }
        for k, (body, message) in enumerate(cases.items()):
            spec = S.write_spec(ARGS.work, f"bad{k}.yaml",
                                f"base: {S.ROOT}/config/scenes/paper_sim3_fixed_free.yaml\n" + body)
            out = os.path.join(ARGS.work, f"bad{k}")
            rc, log = S.sweep(spec, "--out", out, sim=ARGS.sim)
            self.assertEqual(rc, 2, log)
            self.assertIn(f"{spec}: {message}", log)
            self.assertFalse(os.path.exists(os.path.join(out, "results.csv")), "nothing ran")


def main():
    global ARGS
    ARGS = S.parse_args("f3r_sweep_test_")
    return S.run_junit([LocalAndSsh, Faults], ARGS.junit, "sweep")


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""The slurm engine of nodes/sweep on a real single-node Slurm cluster started here.

usage: test_slurm.py --sim FLEX3RPR_SIM [--junit FILE] [--work DIR]

nodes/slurm_cluster starts munged, slurmctld and slurmd from Debian's packages with every file
in one directory (root only: the daemons run as root). Then:
- the 24-run grid of test_sweep.py, submitted as an `sbatch --array` job (6 tasks, after the
  reference job), gives the same results CSV as the local engine, row by row, apart from the
  timing columns; Slurm's own job log says which jobs ran and that each completed;
- the job script carries the spec's array size, time and memory;
- submitted with --no-wait and collected later with --merge, the same rows again;
- running the same sweep again submits nothing.
The cluster is stopped at the end, whatever happened.
"""
import os
import re
import shutil
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sweep_support as S  # noqa: E402

ARGS = None
CLUSTER = os.path.join(S.ROOT, "nodes", "slurm_cluster")
# A short fixed path: munge's socket path must stay under 108 bytes, and a cluster an earlier,
# killed run left behind is stopped by the next start from the same directory.
CLUSTER_DIR = "/tmp/flex3rpr_slurm_test"


def jobcomp():
    """Slurm's record of every finished job: (job id, name, state, array job id or None) a line."""
    path = os.path.join(CLUSTER_DIR, "jobcomp.txt")
    if not os.path.exists(path):
        return []
    out = []
    for line in open(path):
        fields = dict(re.findall(r"(\w+)=(\S*)", line))
        out.append((fields.get("JobId"), fields.get("Name"), fields.get("JobState"), fields.get("ArrayJobId")))
    return out


class SlurmEngine(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.started = False
        if os.geteuid() != 0:
            raise RuntimeError("the Slurm test starts slurmctld and slurmd as root: run it as root, as CI does")
        p = subprocess.run(["bash", CLUSTER, "start", CLUSTER_DIR], capture_output=True, text=True, timeout=600)
        print(p.stdout + p.stderr)
        if p.returncode != 0:
            raise RuntimeError(f"nodes/slurm_cluster start failed:\n{p.stdout}{p.stderr}")
        cls.started = True
        os.environ["SLURM_CONF"] = os.path.join(CLUSTER_DIR, "slurm.conf")
        cls.work = ARGS.work
        cls.spec = S.write_spec(cls.work, "grid24.yaml", S.SPEC24.format(root=S.ROOT, duration=0.02))
        cls.local = os.path.join(cls.work, "local")
        shutil.rmtree(cls.local, ignore_errors=True)
        cls.local_rc, cls.local_log = S.sweep(cls.spec, "--out", cls.local, sim=ARGS.sim)
        cls.out = os.path.join(cls.work, "slurm")
        shutil.rmtree(cls.out, ignore_errors=True)
        cls.rc, cls.log = S.sweep(cls.spec, "--out", cls.out, "--engine", "slurm", sim=ARGS.sim)
        print(cls.log)

    @classmethod
    def tearDownClass(cls):
        if cls.started:
            subprocess.run(["bash", CLUSTER, "stop", CLUSTER_DIR], timeout=600)

    def test_a_the_array_job_gives_the_local_engines_rows(self):
        self.assertEqual(self.local_rc, 0, self.local_log)
        self.assertEqual(self.rc, 0, self.log)
        self.assertIn("24 to run (slurm)", self.log)
        self.assertRegex(self.log, r"submitted \d+, \d+: 24 runs in 6 array tasks")
        rows = S.read_results(self.out)
        self.assertEqual(len(rows), 24)
        self.assertTrue(all(r["status"] == "ok" for r in rows), [r["error"] for r in rows])
        self.assertEqual(S.without_timing(rows), S.without_timing(S.read_results(self.local)))

    def test_b_slurm_ran_the_reference_and_six_array_tasks(self):
        reference_job, array_job = open(os.path.join(self.out, "slurm", "jobs")).read().split()
        jobs = jobcomp()
        self.assertIn((reference_job, "flex3rpr-reference", "COMPLETED", None), jobs)
        tasks = [j for j in jobs if j[3] == array_job]
        self.assertEqual(len(tasks), 6, jobs)
        self.assertTrue(all(name == "flex3rpr-sweep" and state == "COMPLETED" for _, name, state, _ in tasks), tasks)
        outputs = [n for n in os.listdir(os.path.join(self.out, "slurm")) if n.endswith(".out")]
        self.assertEqual(len(outputs), 7, "each array task and the reference job wrote its Slurm output")

    def test_c_the_job_script_carries_the_specs_limits(self):
        script = open(os.path.join(self.out, "slurm", "sweep.sbatch")).read()
        for line in ("#SBATCH --array=0-5", "#SBATCH --time=00:30:00", "#SBATCH --mem=500M",
                     "#SBATCH --cpus-per-task=1"):
            self.assertIn(line + "\n", script)
        self.assertIn("--array-task " + self.out, script)

    def test_d_no_wait_then_merge_gives_the_same_rows(self):
        out = os.path.join(self.work, "slurm_no_wait")
        shutil.rmtree(out, ignore_errors=True)
        rc, log = S.sweep(self.spec, "--out", out, "--engine", "slurm", "--no-wait", sim=ARGS.sim)
        self.assertEqual(rc, 0, log)
        self.assertIn("collect the results with", log)
        job_ids = open(os.path.join(out, "slurm", "jobs")).read().split()
        self.assertEqual(len(job_ids), 2, "the reference job and the array job")

        def gone():
            p = subprocess.run(["squeue", "-h", "-o", "%i", "-j", ",".join(job_ids)], capture_output=True, text=True)
            return p.returncode == 0 and not p.stdout.strip()
        self.assertTrue(S.wait_for(gone, step=0.5), "the jobs never left the queue")
        rc, log = S.sweep(self.spec, "--out", out, "--merge", sim=ARGS.sim)
        self.assertEqual(rc, 0, log)
        self.assertEqual(S.without_timing(S.read_results(out)), S.without_timing(S.read_results(self.local)))

    def test_e_a_rerun_submits_nothing(self):
        before = len(jobcomp())
        rc, log = S.sweep(self.spec, "--out", self.out, "--engine", "slurm", sim=ARGS.sim)
        self.assertEqual(rc, 0, log)
        self.assertIn("24 already in the results, 0 to run", log)
        self.assertNotIn("submitted", log)
        self.assertEqual(len(jobcomp()), before)


def main():
    global ARGS
    ARGS = S.parse_args("f3r_slurm_test_")
    return S.run_junit([SlurmEngine], ARGS.junit, "sweep_slurm")


if __name__ == "__main__":
    sys.exit(main())

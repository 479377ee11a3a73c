#!/usr/bin/env python3
"""rostest of the example controllers in lockstep (nodes/pd_controller, nodes/lqr_controller):
each run is `roslaunch flex3rpr pd_control.launch` (or lqr_) at realtime_factor 0 on its own
master, and the controller's log (every state it answered, repr-exact) is what is compared.

- Two PD runs log the same states bit for bit, the second with CPU hogs busy beside it: the node
  waits for every command, so the scheduler cannot change what happens.
- The LQR (tip deflections weighted) reaches the target and its RMS tip deflection is a tenth of
  the PD's or less (measured: 0.0076 um against 0.41 um over 0.5 s); both stay in the stroke.

No wall times, rates or counts of an observer are asserted; the timeouts only catch a hang."""
import csv
import math
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import unittest

import rostest

RATE = 1000  # sim.launch's publish_rate
TARGET = (0.01, 0.0, 0.0)  # the launch files' default move on rest.yaml: home + 1 cm in x


def free_port():
    s = socket.socket()
    s.bind(("localhost", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def run(launch, log, duration, timeout=900):
    """roslaunch LAUNCH on a master of its own; the controller's log rows."""
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % port)
    out_path = log + ".out"
    with open(out_path, "w") as out:
        p = subprocess.Popen(["roslaunch", "-p", str(port), "flex3rpr", launch, "realtime_factor:=0",
                              "duration:=%r" % duration, "log:=" + log], env=env, stdout=out,
                             stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        try:
            rc = p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            p.terminate()
            p.wait()
            rc = "a hang: still running after %d s" % timeout
    with open(out_path) as f:
        tail = "".join(f.readlines()[-40:])
    if rc != 0 or not os.path.exists(log):
        raise AssertionError("%s ended with %s:\n%s" % (launch, rc, tail))
    with open(log) as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def answered_before(rows, duration):
    """The rows of the states before the duration: the node waited for each of them, so every
    run has them all; the state at the duration itself may come as roslaunch stops."""
    return [r for r in rows if float(r[0]) < duration - 0.5 / RATE]


def column(head, rows, name):
    k = head.index(name)
    return [float(r[k]) for r in rows]


class LockstepControllers(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="lockstep_controllers_")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_pd_runs_are_bit_identical_beside_a_cpu_hog(self):
        duration = 0.2
        head, first = run("pd_control.launch", os.path.join(self.tmp, "pd_1.csv"), duration)
        hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
        try:
            head2, second = run("pd_control.launch", os.path.join(self.tmp, "pd_2.csv"), duration)
        finally:
            for h in hogs:
                h.kill()
                h.wait()
        self.assertEqual(head, head2)
        a, b = answered_before(first, duration), answered_before(second, duration)
        want = int(round(duration * RATE))
        self.assertEqual(len(a), want, "the first run answered %d states before %g s, not %d" % (len(a), duration, want))
        self.assertEqual([r[0] for r in a], ["0.%09d" % (k * 1000000) for k in range(want)])
        for k, (ra, rb) in enumerate(zip(a, b)):
            self.assertEqual(ra, rb, "the runs part at row %d (t = %s):\n%s\n%s" % (k, ra[0], ra, rb))
        self.assertEqual(len(a), len(b))
        # the state at the duration, where both have it, too
        n = min(len(first), len(second))
        self.assertEqual(first[:n], second[:n])
        # and the platform moved toward the target
        x = column(head, a, "x_p")
        self.assertGreater(x[-1], 0.5 * TARGET[0])

    def test_lqr_reaches_the_target_with_less_tip_deflection_than_pd(self):
        duration = 0.5
        result = {}
        for name in ("pd", "lqr"):
            head, rows = run("%s_control.launch" % name, os.path.join(self.tmp, name + ".csv"), duration)
            rows = answered_before(rows, duration)
            self.assertEqual(len(rows), int(round(duration * RATE)))
            x, y = column(head, rows, "x_p"), column(head, rows, "y_p")
            tips = [w for i in (1, 2, 3) for w in column(head, rows, "w_tip_%d" % i)]
            rho = [r for i in (1, 2, 3) for r in column(head, rows, "rho_%d" % i)]
            result[name] = dict(error=math.hypot(x[-1] - TARGET[0], y[-1] - TARGET[1]),
                                rms_tip=math.sqrt(sum(w * w for w in tips) / len(tips)),
                                rho=(min(rho), max(rho)))
            print("%s: final position error %.3g m, RMS tip deflection %.3g m, strokes %.4f..%.4f m"
                  % (name, result[name]["error"], result[name]["rms_tip"], *result[name]["rho"]))
        pd, lqr = result["pd"], result["lqr"]
        # both settle well inside 0.5 s (PD 0.25 s, LQR 0.29 s to 2 % of the move), within the stroke
        self.assertLess(lqr["error"], 1e-4)
        self.assertLess(pd["error"], 2e-4)
        for r in (pd, lqr):
            self.assertGreater(r["rho"][0], 0.0)
            self.assertLess(r["rho"][1], 0.2)
        # the LQR damps the links: measured 50x less, asserted 10x
        self.assertLess(lqr["rms_tip"], 0.1 * pd["rms_tip"])
        self.assertGreater(pd["rms_tip"], 0.0)


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "lockstep_controllers", LockstepControllers)

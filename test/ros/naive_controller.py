#!/usr/bin/env python3
"""rostest: a naive controller in lockstep cannot hang (test/ros/naive_pd.py: it answers every
state at once, with no wait for its publisher's connection and no stamp).

An answer to the latched first state sent before the controller's publisher has connected to the
node is lost; the node then sends the waiting state again when a command publisher connects, so
the run goes on. Each run has its own master; the node runs 2000 periods (2 s at 1 kHz) at full
speed in lockstep, and the controller's log (every state it answered) must be the same bit for
bit in every case:
- the controller started before the node, and after it;
- under record.launch with acknowledge:=false (the recorder subscribes to the command topic too,
  so a controller that waits for get_num_connections() > 0 would be fooled);
- after the node, beside a CPU hog on each core;
- a controller that stamps each answer with its state's stamp and sends it twice: the node takes
  the first and discards the duplicate (unstamped, it would take the next period).
No wall time, rate or message count of an observer is asserted; the timeouts only catch a hang."""
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import unittest

import rosgraph
import rospkg
import rostest

PKG = rospkg.RosPack().get_path("flex3rpr")
HERE = os.path.dirname(os.path.abspath(__file__))
DURATION = 2.0
PERIODS = 2000
SCENE = os.path.join(PKG, "config", "scenes", "rest.yaml")


def free_port():
    s = socket.socket()
    s.bind(("localhost", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class Run:
    """A master of its own, the node (sim.launch, or record.launch) and the naive controller."""

    def __init__(self, tmp, name):
        self.port = free_port()
        self.env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d" % self.port)
        self.log = os.path.join(tmp, name + ".csv")
        self.out = open(os.path.join(tmp, name + ".out"), "w")
        self.procs = []

    def start(self, args):
        p = subprocess.Popen(args, env=self.env, stdout=self.out, stderr=subprocess.STDOUT,
                             stdin=subprocess.DEVNULL)
        self.procs.append(p)
        return p

    def master(self):
        self.start(["roscore", "-p", str(self.port)])
        master = rosgraph.Master("/naive_test", master_uri=self.env["ROS_MASTER_URI"])
        end = time.time() + 60
        while time.time() < end:
            try:
                master.getPid()
                return
            except Exception:
                time.sleep(0.1)
        raise AssertionError("no master on port %d" % self.port)

    def controller(self, *flags):
        return self.start([sys.executable, os.path.join(HERE, "naive_pd.py"), self.log, *flags])

    def node(self, record=None):
        common = ["realtime_factor:=0", "duration:=%g" % DURATION, "scene:=" + SCENE]
        if record:
            return self.start(["roslaunch", "-p", str(self.port), "flex3rpr", "record.launch",
                               "acknowledge:=false", "bag:=" + record] + common)
        return self.start(["roslaunch", "-p", str(self.port), "flex3rpr", "sim.launch",
                           "lockstep:=true", "required:=true"] + common)

    def finish(self, launch, timeout=600):
        try:
            rc = launch.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            rc = "a hang: still running after %d s" % timeout
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
                try:
                    p.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    p.kill()
        self.out.close()
        with open(self.out.name) as f:
            tail = "".join(f.readlines()[-30:])
        rows = open(self.log).read().splitlines() if os.path.exists(self.log) else []
        # a state sent again (its first answer was lost) is answered again, the same row
        answered = [r for k, r in enumerate(rows) if float(r.split(",")[0]) < DURATION - 0.5e-3
                    and (k == 0 or r != rows[k - 1])]
        if rc != 0 or len(answered) != PERIODS:
            raise AssertionError("ended with %s after %d of %d states answered:\n%s"
                                 % (rc, len(answered), PERIODS, tail))
        return answered


class NaiveController(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="naive_controller_")
        cls.runs = {}

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def run_case(self, name, controller_first, record=False, hogs=0, flags=()):
        r = Run(self.tmp, name)
        r.master()
        busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(hogs)]
        try:
            if controller_first:
                r.controller(*flags)
                time.sleep(1.0)  # the controller is up and subscribed before the node exists
            launch = r.node(os.path.join(self.tmp, name + ".bag") if record else None)
            if not controller_first:
                time.sleep(2.0)  # the node has published its first state, latched, and waits
                r.controller(*flags)
            rows = r.finish(launch)
        finally:
            for h in busy:
                h.kill()
                h.wait()
        return rows

    def test_every_start_order_runs_the_same_2000_periods(self):
        cases = [("controller_first", dict(controller_first=True)),
                 ("node_first", dict(controller_first=False)),
                 ("record_acknowledge_false", dict(controller_first=False, record=True)),
                 ("node_first_beside_cpu_hogs", dict(controller_first=False, hogs=os.cpu_count() or 2)),
                 ("stamped_twice", dict(controller_first=False, flags=("--stamped-twice",)))]
        logs = {}
        for name, kwargs in cases:
            with self.subTest(case=name):
                logs[name] = self.run_case(name, **kwargs)
        reference = logs.get("node_first")
        self.assertIsNotNone(reference)
        self.assertEqual(reference[0].split(",")[0], "0.000000000")
        moved = [float(x) for x in reference[-1].split(",")[1:]] != [float(x) for x in reference[0].split(",")[1:]]
        self.assertTrue(moved, "the controller moved the legs")
        for name, rows in logs.items():
            for k, (a, b) in enumerate(zip(reference, rows)):
                self.assertEqual(a, b, "%s parts from node_first at state %d" % (name, k))


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "naive_controller", NaiveController)

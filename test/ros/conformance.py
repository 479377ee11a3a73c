#!/usr/bin/python3
"""The CLI (a --hold table), the node (~step_with_command, ~set_state) and Python (Sim.step,
set_state) on one scene: the same path to the bit (end stops reached, sensors on), the same
refusal of every bad input, word for word and naming the same value, with nothing changed; and
a failed step that leaves node and Python where they were.

  a  paths: a seeded schedule of commands with end-stop impacts and refusals mid-run; node and
     Python equal to the bit at every call, the CLI's CSV equal to Python at its 15 digits
  b  bad inputs: 27 commands, periods and states refused by node, Python and (where it has the
     input) the CLI with the same message, each followed by a step that both take alike
  c  a failed step: a leg pulled in until it collapses, in node and Python at the same call,
     both left at the last good state, and the CLI stopping on the same error
"""
import csv
import math
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import rospy
import rostest

import flex3rpr
from flex3rpr.msg import EffortCommand
from flex3rpr.srv import SetState, StepWithCommand

PKG = os.path.realpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
PERIOD = 1e-3  # the nodes' publish period (1000 Hz), Python's default
NAN, INF = float("nan"), float("inf")


def cli():
    path = os.path.join(os.environ.get("F3R_DEVEL", ""), "lib/flex3rpr/flex3rpr_sim")
    if os.path.exists(path):
        return path
    return subprocess.check_output(["catkin_find", "--first-only", "flex3rpr", "flex3rpr_sim"],
                                   text=True).strip()


def run_cli(scene, args):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run.csv")
        p = subprocess.run([cli(), scene, "--out", out, "--stop-at-outputs",
                            "--output-step", repr(PERIOD)] + args,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=600)
        rows = list(csv.DictReader(open(out))) if os.path.exists(out) else []
    return p.returncode, p.stderr, rows


class Shells:
    """A node and a Python Sim on the same scene, given the same calls."""

    def __init__(self, test, node, scene):
        self.test = test
        rospy.wait_for_service("/%s/step_with_command" % node, timeout=120)
        rospy.wait_for_service("/%s/set_state" % node, timeout=120)
        self.node_step = rospy.ServiceProxy("/%s/step_with_command" % node, StepWithCommand)
        self.node_set = rospy.ServiceProxy("/%s/set_state" % node, SetState)
        self.sim = flex3rpr.Sim(scene, period=PERIOD)
        self.calls = 0

    def step(self, command, periods=1):
        """The command (EffortCommand's fields) for `periods` in both: both take it, with the
        same state after it to the bit, or both refuse it with the same message. Returns
        Python's message, or None."""
        self.calls += 1
        res = self.node_step(command=EffortCommand(**command), periods=periods)
        try:
            self.sim.step(command, periods=periods)
            error = None
        except (flex3rpr.Error, ValueError) as e:
            error = str(e)
        where = "call %d (%r, %r periods)" % (self.calls, command, periods)
        self.test.assertEqual(res.success, error is None,
                              "%s: node %r, Python %r" % (where, res.message, error))
        if error is not None:
            self.test.assertEqual(res.message, error, where)
            return error
        s = self.sim.state
        self.test.assertEqual(res.sim_time, s.t, where)
        self.test.assertEqual(list(res.platform_pose), s.pose.tolist(), where)
        self.test.assertEqual(list(res.platform_twist), s.twist.tolist(), where)
        self.test.assertEqual(list(res.modal), s.modal.tolist(), where)
        self.test.assertEqual(list(res.modal_rate), s.modal_rate.tolist(), where)
        return None

    def set_state(self, pose, twist=(0.0, 0.0, 0.0), modal=(), modal_rate=()):
        """Both set it or both refuse it with the same message; returns Python's, or None."""
        res = self.node_set(platform_pose=list(pose), platform_twist=list(twist),
                            modal=list(modal), modal_rate=list(modal_rate))
        try:
            self.sim.set_state(pose, twist, list(modal) or None, list(modal_rate) or None)
            error = None
        except (flex3rpr.Error, ValueError) as e:
            error = str(e)
        self.test.assertEqual(res.success, error is None, "node %r, Python %r" % (res.message, error))
        if error is not None:
            self.test.assertEqual(res.message, error)
        return error


def schedule(seed):
    """(periods, command) pairs: random leg forces and cylinder torques, then each leg pushed
    out and pulled in hard enough to reach its end stops."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(6):
        out.append((int(rng.integers(3, 12)),
                    {"leg_force": rng.normal(0.0, 40.0, 3).tolist(),
                     "cylinder_torque": rng.normal(0.0, 0.05, 3).tolist()}))
    out.append((60, {"leg_force": [300.0, -100.0, -100.0], "cylinder_torque": [0.0, 0.0, 0.0]}))
    out.append((60, {"leg_force": [-300.0, 100.0, 100.0], "cylinder_torque": [0.0, 0.02, 0.0]}))
    out.append((10, {"leg_force": [0.0, 0.0, 0.0], "cylinder_torque": [0.0, 0.0, 0.0]}))
    return out


class Conformance(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("conformance", anonymous=True)
        cls.stops_scene = os.path.join(PKG, "test", "scenes", "conformance.yaml")
        cls.free_scene = os.path.join(PKG, "test", "scenes", "sensors_fixed_free.yaml")

    def test_a_one_path_in_every_shell(self):
        shells = Shells(self, "stops", self.stops_scene)
        python = flex3rpr.Sim(self.stops_scene, period=PERIOD)  # one period a call, for the CLI
        rows, holds, t = [], [], 0
        for k, (periods, command) in enumerate(schedule(11)):
            if k == 3:  # a refused command mid-run changes nothing
                bad = dict(command, leg_force=[0.0, 5000.0, 0.0])
                self.assertIn("leg_force_2 is 5000, out of range -1000..1000 (the scene's "
                              "limits.force)", shells.step(bad))
            self.assertIsNone(shells.step(command, periods))
            values = command["leg_force"] + command["cylinder_torque"]
            for n, v in enumerate(values):
                holds += ["--hold", "%r:%d:%r" % (t * PERIOD, n, v)]
            for _ in range(periods):
                python.step(command)
                rows.append((python.state, python.sensors))
            t += periods
        self.assertGreater(shells.sim.extras["impacts"], 5, "the schedule reaches the end stops")
        self.assertTrue(np.array_equal(python.state.vector, shells.sim.state.vector),
                        "one step of n periods is n steps of one")
        code, err, csv_rows = run_cli(self.stops_scene, ["--duration", repr(t * PERIOD)] + holds)
        self.assertEqual(code, 0, err)
        self.assertEqual(len(csv_rows), t + 1)
        names = python.sensor_names
        for k, (state, sensors) in enumerate(rows):
            row = csv_rows[k + 1]
            for name, value in (("x_p", state.pose[0]), ("y_p", state.pose[1]),
                                ("phi_p", state.pose[2]), ("rho_1", state.q[0]),
                                ("theta_3", state.q[5]), ("eta_2_1", state.modal[2])):
                self.assertEqual(row[name], "%.15g" % value, "period %d, %s" % (k + 1, name))
            for name, value in zip(names, sensors):
                self.assertEqual(row[name], "%.15g" % value, "period %d, %s" % (k + 1, name))

    def test_b_every_bad_input_is_refused_alike(self):
        shells = Shells(self, "refusals", self.stops_scene)
        zero = {"leg_force": [0.0, 0.0, 0.0]}
        commands = [  # (command, what the refusal says)
            ({"leg_force": [NAN, 0.0, 0.0]}, "leg_force_1 is nan, not finite"),
            ({"leg_force": [0.0, 0.0, INF]}, "leg_force_3 is inf, not finite"),
            ({"cylinder_torque": [0.0, -INF, 0.0]}, "cylinder_torque_2 is -inf, not finite"),
            ({"platform": [0.0, NAN, 0.0]}, "platform_force_y is nan, not finite"),
            ({"modal": [NAN, 0, 0, 0, 0, 0]}, "modal_force[0] is nan, not finite"),
            ({"leg_force": [0.0, 5000.0, 0.0]},
             "leg_force_2 is 5000, out of range -1000..1000 (the scene's limits.force)"),
            ({"leg_force": [-1000.5, 0.0, 0.0]}, "leg_force_1 is -1000.5, out of range"),
            ({"cylinder_torque": [150.0, 0.0, 0.0]},
             "cylinder_torque_1 is 150, out of range -100..100 (the scene's limits.torque)"),
            ({"platform": [0.0, 0.0, 101.0]}, "platform_torque is 101, out of range -100..100"),
            ({"platform": [1e300, 0.0, 0.0]}, "platform_force_x is 1e+300, out of range"),
            ({"modal": [0, 0, 0, 2000.0, 0, 0]},
             "modal_force[3] is 2000, out of range -1000..1000 (the scene's limits.modal_force)"),
            ({"modal": [0.0] * 5}, "modal has 5 values, expected 0 or 6"),
        ]
        periods = [(0, "periods is 0: a whole number in 1..1e9 expected"),
                   (2000000000, "periods is 2e+09: a whole number in 1..1e9 expected")]
        states = [  # (set_state's arguments, what the refusal says)
            (([2.0, 0.0, 0.0],), "pose[0] is 2: out of range -1..1"),
            (([0.0, NAN, 0.3],), "pose[1] is nan: out of range -1..1"),
            (([0.0, 0.0, 1e6],), "pose[2] is 1e+06: out of range -1000..1000 rad"),
            (([0.0, 0.0, 0.3], [0.0, 0.0, INF]), "twist[2] is inf: out of range"),
            (([0.0, 0.0, 0.3], [0.0, 0.0, 0.0], [0, 0, 1.0, 0, 0, 0]),
             "modal[2] is 1: out of range -0.1..0.1"),
            (([0.0, 0.0, 0.3], [0.0, 0.0, 0.0], [0.0] * 6, [1000.0, 0, 0, 0, 0, 0]),
             "modal_rate[0] is 1000: out of range -100..100"),
            (([0.0, 0.0, 0.3], [0.0, 0.0, 0.0], [0.0] * 5),
             "modal: 5 values, the model has 6 modal coordinates"),
            (([0.0, 0.0, 0.3], [0.0, 0.0, 0.0], [0.0] * 6, [0.0] * 5),
             "modal and modal_rate: 6 and 5 values"),
            (([0.3, 0.0, 0.0],), "beyond the end stops"),
        ]
        refused = 0
        for k, (command, says) in enumerate(commands):
            self.assertIn(says, shells.step(command) or "accepted", command)
            self.assertIsNone(shells.step({"leg_force": [10.0 * k, 0.0, -5.0]}))  # unchanged
            refused += 1
        for n, says in periods:
            self.assertIn(says, shells.step(zero, n) or "accepted")
            self.assertIsNone(shells.step(zero))
            refused += 1
        for args, says in states:
            self.assertIn(says, shells.set_state(*args) or "accepted", args)
            self.assertIsNone(shells.step({"leg_force": [0.0, 3.0, 0.0]}))
            refused += 1
        # Python's own inputs, which a message cannot carry: refused the same way
        for bad_periods in (2.9, -3, NAN):
            with self.assertRaises(flex3rpr.ArgumentError) as e:
                shells.sim.step(zero, periods=bad_periods)
            self.assertIn("a whole number in 1..1e9 expected", str(e.exception))
            refused += 1
        # the CLI: the same command rule on its --hold table, and the scene's ranges
        for hold, says in (("0.002:1:5000", commands[5][1]), ("0.001:0:nan", commands[0][1]),
                           ("0.001:8:101", "platform_torque is 101, out of range -100..100"),
                           ("0.001:12:2000", commands[10][1]),
                           ("0.001:15:1", "index 15 is out of range 0..14")):
            code, err, _ = run_cli(self.stops_scene, ["--duration", "0.005", "--hold", hold])
            self.assertEqual(code, 2, err)
            self.assertIn(says, err)
            refused += 1
        for field, says in (("initial.platform_pose=[2, 0, 0.3]",
                             "initial.platform_pose[0]: 2 is out of range"),
                            ("limits.force=-1", "limits.force: -1 is out of range 1e-06..1e+09")):
            code, err, _ = run_cli(self.stops_scene, ["--duration", "0.005", "--set", field])
            self.assertNotEqual(code, 0, err)
            self.assertIn(says, err)
            refused += 1
        self.assertGreaterEqual(refused, 20)

    def test_c_a_failed_step_leaves_node_and_python_where_they_were(self):
        shells = Shells(self, "free", self.free_scene)
        self.assertIsNone(shells.step({"leg_force": [2.0, 0.0, 0.0],
                                       "cylinder_torque": [0.0, 0.01, 0.0]}, 5))
        error = None
        for _ in range(2000):  # one period a call: each call fails in both, or in neither
            error = shells.step({"leg_force": [-1000.0, 0.0, 0.0]})
            if error:
                break
        self.assertIsNotNone(error, "the leg never collapsed")
        self.assertIn("collapsed", error)
        failed_at = shells.sim.t
        self.assertEqual(shells.sim.t, failed_at, "the failed period was undone")
        # the leg moves inwards too fast for any command to stop it within a period: both
        # refuse it alike again, then go on from a state set anew
        self.assertIn("collapsed", shells.step({"leg_force": [1000.0, 0.0, 0.0]}))
        self.assertIsNone(shells.set_state([0.0, 0.0, 0.0]))
        for k in range(5):
            self.assertIsNone(shells.step({"leg_force": [0.5 * k + 0.1, 0.0, 0.0]}))
        self.assertAlmostEqual(shells.sim.t, failed_at + 5 * PERIOD, places=12)
        code, err, rows = run_cli(self.free_scene, ["--duration", "3", "--hold", "0.005:0:-1000"])
        self.assertEqual(code, 1, err)
        self.assertIn("collapsed", err)


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "conformance", Conformance, sys.argv)

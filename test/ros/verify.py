#!/usr/bin/python3
"""~verify: with an accuracy request the node steps the check configuration on the same commands
on a thread of its own, and reports what Python's session measures on the same commands, to the
bit: ~status.measured_error_m and request_met, and /diagnostics.

  a  a step PD's commands through ~step_with_command: the node's measured error equals
     flex3rpr.Sim's; a modal ~set_state ends the measurement (NaN, a note); ~reset starts anew
  b  a request the scene's fixed modes cannot meet: request_met false, a WARN on /diagnostics
     naming the request, latched while the run goes on
  c  ~verify false: the estimate alone, as before
"""
import math
import os
import sys
import time
import unittest

import numpy as np
import rospy
import rostest

import flex3rpr
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from flex3rpr.msg import EffortCommand, SimStatus
from flex3rpr.srv import SetState, StepWithCommand
from std_srvs.srv import Trigger

PKG = os.path.realpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
SCENE = os.path.join(PKG, "config", "scenes", "rest_turned.yaml")


class Node:
    def __init__(self, name):
        self.name = name
        self.status, self.diagnostics = [], []
        rospy.Subscriber("/%s/status" % name, SimStatus, self.status.append, queue_size=10000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.diagnostics.append, queue_size=10000)
        rospy.wait_for_service("/%s/step_with_command" % name, timeout=120)
        self.step = rospy.ServiceProxy("/%s/step_with_command" % name, StepWithCommand)
        self.set_state = rospy.ServiceProxy("/%s/set_state" % name, SetState)
        self.reset = rospy.ServiceProxy("/%s/reset" % name, Trigger)

    def settled(self, t, since=0, timeout=300.0):
        """The first ~status at simulated time t with every period checked, from the since-th
        on (a run before a ~reset passed the same times)."""
        end = time.time() + timeout
        while time.time() < end:
            for m in list(self.status)[since:]:
                if m.sim_time == t and m.measurement_pending == 0:
                    return m
            time.sleep(0.05)
        self.fail = True
        raise AssertionError("%s: no settled ~status at t = %r" % (self.name, t))


def step_pd(node, periods, python):
    """A PD on the strokes towards a pose that moves and turns the platform, the commands from
    Python's state; the node's state stays Python's to the bit."""
    target = python.state.q[:3] + np.array([0.01, -0.006, 0.004])
    for _ in range(periods):
        u = 4000.0 * (target - python.state.q[:3]) - 60.0 * python.state.v[:3]
        legs = np.clip(u, -900.0, 900.0).tolist()
        res = node.step(command=EffortCommand(leg_force=legs), periods=1)
        assert res.success, res.message
        python.step({"leg_force": legs})
        assert list(res.platform_pose) == python.state.pose.tolist(), (res.sim_time, res.platform_pose,
                                                                      python.state.pose)
    return res


class Verify(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("verify", anonymous=True)

    def test_a_the_node_measures_what_python_measures(self):
        node = Node("verified")
        python = flex3rpr.Sim(SCENE, accuracy=1e-5, period=1e-3)
        res = step_pd(node, 80, python)
        status = node.settled(res.sim_time)
        self.assertEqual(status.error_basis, "measured")
        self.assertGreater(python.measured_error_m, 0.0)
        self.assertEqual(status.measured_error_m, python.measured_error_m)
        self.assertEqual(status.request_met, python.request_met)
        self.assertEqual(status.measurement_note, "")
        # a modal state ends the measurement, in both
        modal = [1e-4, 0, 0, 0, 0, 0]
        self.assertTrue(node.set_state(platform_pose=list(python.state.pose), modal=modal).success)
        python.set_state(python.state.pose, modal=modal)
        res = step_pd(node, 2, python)
        status = node.settled(res.sim_time)
        self.assertTrue(math.isnan(status.measured_error_m))
        self.assertTrue(math.isnan(python.measured_error_m))
        self.assertIn("modal state", status.measurement_note)
        self.assertFalse(status.request_met)
        # ~reset starts a new measurement
        self.assertTrue(node.reset().success)
        python.reset()
        end = time.time() + 120
        while time.time() < end and not any(m.sim_time == 0.0 and m.measurement_note == ""
                                            for m in node.status[-5:]):
            time.sleep(0.05)
        since = len(node.status)
        res = step_pd(node, 10, python)
        status = node.settled(res.sim_time, since)
        self.assertEqual(status.measured_error_m, python.measured_error_m)
        self.assertEqual(status.measurement_note, "")

    def test_b_a_missed_request_warns_and_stays(self):
        node = Node("strict")
        python = flex3rpr.Sim(SCENE, accuracy=1e-9, period=1e-3)
        res = step_pd(node, 30, python)
        status = node.settled(res.sim_time)
        self.assertFalse(status.request_met)
        self.assertGreater(status.measured_error_m, 0.7e-9)
        self.assertEqual(status.measured_error_m, python.measured_error_m)
        end = time.time() + 120
        warned = lambda: [s for m in node.diagnostics for s in m.status
                          if s.name.startswith("/strict") and s.level == DiagnosticStatus.WARN
                          and "accuracy request 1e-09 m not met" in s.message]
        while time.time() < end and not warned():
            time.sleep(0.1)
        self.assertTrue(warned(), "no WARN on /diagnostics")
        values = {kv.key: kv.value for kv in warned()[-1].values}
        self.assertEqual(values["error_basis"], "measured")
        self.assertEqual(values["request_met"], "false")
        res = step_pd(node, 5, python)  # latched: the largest distance so far only grows
        self.assertFalse(node.settled(res.sim_time).request_met)

    def test_c_verify_false_keeps_the_estimate(self):
        node = Node("unverified")
        python = flex3rpr.Sim(SCENE, accuracy=1e-5, period=1e-3,
                              overrides={"accuracy.verify": False})
        res = step_pd(node, 5, python)
        end = time.time() + 120
        while time.time() < end and not any(m.sim_time == res.sim_time for m in node.status):
            time.sleep(0.05)
        status = [m for m in node.status if m.sim_time == res.sim_time][-1]
        self.assertEqual(status.error_basis, "estimated")
        self.assertEqual(status.measured_error_m, 0.0)
        self.assertIsNone(python.measured_error_m)


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "verify", Verify, sys.argv)

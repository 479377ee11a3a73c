#!/usr/bin/python3
"""flex3rpr.Sim.step against the node's ~step_with_command: 400 calls of varying commands and
period counts, every state equal to the bit (time, joints, pose, twist, modal coordinates), and the last
~state's outputs equal to Python's State row, column for column."""
import os
import sys
import time
import unittest

import numpy as np
import rospy
import rostest

import flex3rpr
from flex3rpr.msg import EffortCommand, FullState
from flex3rpr.srv import StepWithCommand

NODE = "/flex3rpr_node"


class PythonEqualsNode(unittest.TestCase):
    def test_the_step_loops_agree_to_the_bit(self):
        rospy.init_node("python_equals_node", anonymous=True)
        rospy.wait_for_service(NODE + "/step_with_command", timeout=120)
        step = rospy.ServiceProxy(NODE + "/step_with_command", StepWithCommand)
        scene = rospy.get_param(NODE + "/scene")
        overrides = {"effects.end_stops": {}} if rospy.get_param(NODE + "/end_stops") else {}
        sim = flex3rpr.Sim(scene, overrides=overrides,
                           period=1.0 / rospy.get_param(NODE + "/publish_rate", 1000.0))
        rng = np.random.default_rng(7)
        for k in range(400):
            legs = rng.normal(0.0, 20.0, 3)
            torques = rng.normal(0.0, 0.05, 3)
            periods = int(rng.integers(1, 4))
            res = step(command=EffortCommand(leg_force=legs.tolist(),
                                             cylinder_torque=torques.tolist()), periods=periods)
            self.assertTrue(res.success, res.message)
            s = sim.step({"leg_force": legs, "cylinder_torque": torques}, periods=periods)
            self.assertEqual(res.sim_time, s.t, "call %d" % k)
            self.assertEqual(list(res.platform_pose), s.pose.tolist(), "call %d" % k)
            self.assertEqual(list(res.platform_twist), s.twist.tolist(), "call %d" % k)
            self.assertEqual(list(res.modal), s.modal.tolist(), "call %d" % k)
            self.assertEqual(list(res.modal_rate), s.modal_rate.tolist(), "call %d" % k)
            names = list(res.joint_state.name)
            for i in range(3):
                self.assertEqual(res.joint_state.position[names.index("leg_%d_prismatic" % (i + 1))],
                                 s.q[i])
                self.assertEqual(res.joint_state.position[names.index("leg_%d_revolute" % (i + 1))],
                                 s.q[3 + i])
        # ~state's outputs are the CSV's row, which Python's State holds: one table of columns
        self.assertEqual(rospy.get_param(NODE + "/output_columns"), sim.columns)
        latest = []
        rospy.Subscriber(NODE + "/state", FullState, latest.append)  # latched in lockstep
        deadline = time.time() + 120
        while time.time() < deadline and not (latest and latest[-1].sim_time == s.t):
            time.sleep(0.05)
        self.assertTrue(latest and latest[-1].sim_time == s.t, "no ~state at t = %g" % s.t)
        self.assertEqual(list(latest[-1].outputs), s.vector.tolist())


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "python_equals_node", PythonEqualsNode, sys.argv)

#!/usr/bin/env python3
"""rostest of flex3rpr_node in lockstep: the test is the controller, so the node waits for it
and every state it publishes reaches this process before the next period exists."""
import json
import math
import os
import subprocess
import tempfile
import threading
import unittest
import xml.etree.ElementTree as ET

import rospkg
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import JointState
from std_srvs.srv import Empty, Trigger

from flex3rpr.msg import EffortCommand, FullState, SimStatus
from flex3rpr.srv import Linearise, SetState, StepWithCommand
from wall_wait import wait_for

NODE = "/flex3rpr_node"
PKG = rospkg.RosPack().get_path("flex3rpr")
PERIODS = 30


def command(k):
    """The k-th period's command: a deterministic, varying push on the legs and cylinders."""
    return EffortCommand(leg_force=[3.0 * math.sin(0.3 * k), -2.0, 1.0 + 0.1 * k],
                         cylinder_torque=[0.2, -0.1 * math.cos(0.2 * k), 0.0])


def state(js):
    return tuple(js.position) + tuple(js.velocity) + tuple(js.effort)


class Lockstep(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("lockstep_services", anonymous=True)
        cls.lock = threading.Lock()
        cls.states = {}       # stamp -> joint state tuple, while this test answers as controller
        cls.full = {}         # stamp -> ~state, the same periods
        cls.answering = True
        cls.answers = 0
        cls.status = None
        cls.diagnostics = []
        cls.pub = rospy.Publisher(NODE + "/command", EffortCommand, queue_size=100)
        rospy.Subscriber(NODE + "/status", SimStatus, cls._status, queue_size=None)
        rospy.Subscriber(NODE + "/state", FullState, cls._full, queue_size=None)
        rospy.Subscriber("/diagnostics", DiagnosticArray, cls._diagnostics, queue_size=None)
        wait_for(lambda: cls.pub.get_num_connections() > 0, 60, "the node's command subscription")
        # Subscribed only once the publisher is connected: the latched state at t = 0 then
        # arrives, and its answer cannot be lost.
        rospy.Subscriber("/joint_states", JointState, cls._joints, queue_size=None)
        for name in ("pause", "reset", "step_with_command", "set_state", "linearise"):
            rospy.wait_for_service(NODE + "/" + name, timeout=60)
        cls.pause = rospy.ServiceProxy(NODE + "/pause", Empty)
        cls.reset = rospy.ServiceProxy(NODE + "/reset", Trigger)
        cls.step = rospy.ServiceProxy(NODE + "/step_with_command", StepWithCommand)
        cls.set_state = rospy.ServiceProxy(NODE + "/set_state", SetState)
        cls.linearise = rospy.ServiceProxy(NODE + "/linearise", Linearise)

    @classmethod
    def _joints(cls, m):
        with cls.lock:
            if not cls.answering:
                return
            k = int(round(m.header.stamp.to_sec() * 1000.0))
            cls.states[k] = state(m)
            if cls.answers < PERIODS:
                cls.pub.publish(command(cls.answers))
                cls.answers += 1

    @classmethod
    def _full(cls, m):
        with cls.lock:
            if cls.answering:
                cls.full[int(round(m.header.stamp.to_sec() * 1000.0))] = m

    @classmethod
    def _status(cls, m):
        with cls.lock:
            cls.status = m

    @classmethod
    def _diagnostics(cls, m):
        with cls.lock:
            cls.diagnostics.extend(m.status)

    def sim_time(self):
        with self.lock:
            return self.status.sim_time if self.status else -1.0

    def restart(self):
        """Paused at t = 0, this test no longer answering."""
        with self.lock:
            self.__class__.answering = False
        self.pause()
        self.reset()
        wait_for(lambda: self.sim_time() == 0.0 and self.status.paused, 60, "the reset to t = 0")

    def test_a_topics_then_a_stall_then_the_step_service_gives_the_same_states(self):
        wait_for(lambda: len(self.states) > PERIODS, 300, "%d periods in lockstep" % PERIODS)
        # This controller stopped answering after PERIODS commands: the node waits, and says so.
        wait_for(lambda: self.status.waiting_for_command > 0.0, 120, "~status.waiting_for_command")
        wait_for(lambda: any(d.level == d.WARN and "lockstep" in d.message for d in self.diagnostics),
                 120, "a WARN on /diagnostics")
        self.assertAlmostEqual(self.sim_time(), PERIODS * 0.001, delta=1e-12)
        wait_for(lambda: len(self.full) > PERIODS, 60, "~state of every period")
        with self.lock:
            topics, full = dict(self.states), dict(self.full)
        self.restart()
        for k in range(PERIODS):
            res = self.step(command=command(k), periods=1)
            self.assertTrue(res.success, res.message)
            self.assertAlmostEqual(res.sim_time, (k + 1) * 0.001, delta=1e-12)
            self.assertEqual(state(res.joint_state), topics[k + 1], "period %d" % (k + 1))
            # ~state holds the step's answer, and joint_states' numbers, in one message
            f = full[k + 1]
            self.assertEqual(state(f.joint_state), topics[k + 1], "~state, period %d" % (k + 1))
            self.assertEqual(f.sim_time, res.sim_time)
            for field in ("platform_pose", "platform_twist", "modal", "modal_rate"):
                self.assertEqual(tuple(getattr(f, field)), tuple(getattr(res, field)), field)
        res = self.step(command=EffortCommand(leg_force=[float("nan"), 0, 0]), periods=1)
        self.assertFalse(res.success)
        self.assertIn("leg_force", res.message)

    def test_b_set_state_errors_leave_the_state_unchanged(self):
        pose, twist = [0.004, -0.002, 0.01], [0.0, 0.0, 0.0]

        def run(bad_calls):
            self.restart()
            res = self.set_state(platform_pose=pose, platform_twist=twist)
            self.assertTrue(res.success, res.message)
            for bad in bad_calls:
                res = self.set_state(**bad)
                self.assertFalse(res.success, bad)
                self.assertIn("nothing changed", res.message)
                self.assertEqual(res.message.count("nothing changed"), 1, res.message)
                if bad["platform_pose"][2] == 1e6:
                    self.assertIn("pose[2] is 1e+06: out of range -1000..1000 rad", res.message)
                if len(bad.get("modal", [])) == 9:
                    self.assertIn("modal[0] is 1: out of range -0.1..0.1", res.message)
            res = self.step(command=EffortCommand(leg_force=[1.0, 0.0, 0.0]), periods=5)
            self.assertTrue(res.success, res.message)
            return res

        bad = [dict(platform_pose=[2.0, 0.0, 0.0], platform_twist=twist),   # out of reach
               dict(platform_pose=[0.0, float("nan"), 0.0], platform_twist=twist),
               dict(platform_pose=pose, platform_twist=twist, modal=[0.001]),  # wrong length
               # the session's ranges, flex3rpr.Sim.set_state's (flex3rpr/session.h)
               dict(platform_pose=[0.0, 0.0, 1e6], platform_twist=twist),
               dict(platform_pose=pose, platform_twist=twist, modal=[1.0] + [0.0] * 8)]
        with_errors, without = run(bad), run([])
        self.assertEqual(state(with_errors.joint_state), state(without.joint_state))
        self.assertEqual(list(with_errors.modal), list(without.modal))
        # the pose set holds the loop closed: the platform stands where it was put (the push is small)
        self.assertLess(math.hypot(without.platform_pose[0] - pose[0], without.platform_pose[1] - pose[1]), 1e-4)

    def test_c_linearise_equals_the_cli(self):
        self.restart()
        res = self.linearise()
        self.assertTrue(res.success, res.message)
        out = os.path.join(tempfile.mkdtemp(), "plant.mat")
        cli = os.path.join(os.environ.get("F3R_DEVEL", ""), "lib/flex3rpr/flex3rpr_sim")
        if not os.path.exists(cli):
            cli = subprocess.check_output(["catkin_find", "--first-only", "flex3rpr", "flex3rpr_sim"],
                                          text=True).strip()
        subprocess.check_call([cli, os.path.join(PKG, "test/scenes/idle_fixed_pinned.yaml"),
                               "--linearise", out], stdout=subprocess.DEVNULL)
        with open(out[:-4] + ".json") as f:
            plant = json.load(f)
        self.assertEqual(list(res.state_names), plant["state_names"])
        self.assertEqual(list(res.input_names), plant["input_names"])
        self.assertEqual(list(res.output_names), plant["output_names"])
        for name in ("A", "B", "C", "D"):
            rows = plant[name]
            flat = [v for row in rows for v in row]
            got = list(getattr(res, name))
            self.assertEqual(len(got), len(flat), name)
            scale = max(1.0, max(abs(v) for v in flat))
            for a, b in zip(got, flat):
                self.assertLessEqual(abs(a - b), 1e-12 * scale, name)

    def test_d_end_stops_hold_the_stroke(self):
        urdf = ET.fromstring(rospy.get_param("/robot_description"))
        limits = {}
        for j in urdf.iter("joint"):
            if j.get("name").endswith("_prismatic"):
                limits[j.get("name")] = (float(j.find("limit").get("lower")), float(j.find("limit").get("upper")))
        self.restart()
        # 500 N outward on leg 1 for 30 ms, then coasting: a free leg would leave its stroke.
        nearest = float("inf")
        for k in range(40):
            push = 500.0 if k < 6 else 0.0
            res = self.step(command=EffortCommand(leg_force=[push, 0.0, 0.0]), periods=5)
            self.assertTrue(res.success, res.message)
            js = res.joint_state
            for name, (lower, upper) in limits.items():
                rho = js.position[list(js.name).index(name)]
                self.assertGreaterEqual(rho, lower - 1e-6, name)
                self.assertLessEqual(rho, upper + 1e-6, name)
                nearest = min(nearest, rho - lower, upper - rho)
        self.assertLess(nearest, 1e-3, "the push must carry a leg to a stop")
        # 50 N held outwards on leg 1: the stop holds the leg and reports its force, which pushes
        # back. This scene has neither friction nor beam damping: the beams' vibration swings the
        # stop force, and where it would pull the leg leaves its stop for a moment and is pushed
        # back (test_end_stops checks the force against the statics in a damped scene). So after
        # 2 s the test steps one period at a time to a period that ends with the leg locked.
        res = self.step(command=EffortCommand(leg_force=[50.0, 0.0, 0.0]), periods=2000)
        self.assertTrue(res.success, res.message)
        for _ in range(2000):
            wait_for(lambda: self.sim_time() == res.sim_time, 60, "~status after the held push")
            with self.lock:
                status = self.status
            if status.stop_locked[0] == 1:
                break
            js = res.joint_state
            for name, (lower, upper) in limits.items():
                self.assertLessEqual(js.position[list(js.name).index(name)], upper + 1e-9, name)
            res = self.step(command=EffortCommand(leg_force=[50.0, 0.0, 0.0]), periods=1)
            self.assertTrue(res.success, res.message)
        self.assertEqual(status.stop_locked[0], 1, "leg 1 never locked on its stop under a held 50 N")
        self.assertLess(status.stop_force[0], 0.0)
        js = res.joint_state
        names = list(js.name)
        leg1 = max(limits, key=lambda n: js.position[names.index(n)])
        self.assertAlmostEqual(js.position[names.index(leg1)], limits[leg1][1], delta=1e-9)
        self.assertEqual(js.effort[names.index(leg1)], 50.0)  # the actuator's, not the reaction

if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "lockstep_services", Lockstep)

#!/usr/bin/env python3
"""rostest (default_launch.test): sim.launch starts away from the singular home pose, honours
initial_pose and names a bad one; a node whose state stands (paused, or a lockstep period waiting
for its command) under simulated time still warns, and gives a late tf2 listener its frames.

  a  the default launch (rest_turned.yaml) is non-singular: ~status.actuation_condition is below
     1e3 (home: about 1e16), and ~odom is at the scene's pose (0, 0, 0.3)
  b  initial_pose:=0.01,0.005,0.2 is the platform's pose in ~odom and in TF
  c  a bad initial_pose (two numbers, NaN, text, out of range, unreachable, beyond the end stops)
     stops the node with an error naming ~initial_pose, through roslaunch too
  d  the "waiting for command" warning reaches /rosout under simulated time
  e  a tf2 listener started after the node, while it waits (lockstep) or is paused, resolves
     base -> platform and the beam points, without TF_REPEATED_DATA, and the node has not moved

Nothing depends on the machine's speed: the time limits only catch a hang."""
import math
import os
import socket
import subprocess
import threading
import unittest

import rospkg
import rospy
import rostest
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Log

from flex3rpr.msg import SimStatus
from wall_wait import wait_for

PKG = rospkg.RosPack().get_path("flex3rpr")
REST = os.path.join(PKG, "config", "scenes", "rest.yaml")
IDLE_RIGID = os.path.join(PKG, "test", "scenes", "idle_rigid.yaml")
LATE_LISTENER = """
import sys, time, math, rospy, tf2_ros
rospy.init_node("late_listener", anonymous=True)
buf = tf2_ros.Buffer()
tf2_ros.TransformListener(buf)
prefix = sys.argv[1]
frames = [(prefix + "base", prefix + "platform"), ("world", prefix + "leg_2_beam_10")]
end = time.time() + 300
while time.time() < end and not all(buf.can_transform(a, b, rospy.Time(0)) for a, b in frames):
    time.sleep(0.05)
for a, b in frames:
    if buf.can_transform(a, b, rospy.Time(0)):
        t = buf.lookup_transform(a, b, rospy.Time(0))
        q = t.transform.rotation
        print("resolved %s %s %.12f %.12f %.12f %d" % (a, b, t.transform.translation.x,
              t.transform.translation.y, 2 * math.atan2(q.z, q.w), t.header.stamp.to_nsec()))
time.sleep(1.0)  # a repeated stamp arriving now would still be reported
"""


def yaw(q):
    return 2.0 * math.atan2(q.z, q.w)


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


class Latest:
    """The latest message on a topic, and every one that matches keep."""

    def __init__(self, topic, mtype, keep=None):
        self.lock = threading.Lock()
        self.msg, self.kept, self.keep = None, [], keep
        self.sub = rospy.Subscriber(topic, mtype, self._on, queue_size=None)

    def _on(self, m):
        with self.lock:
            self.msg = m
            if self.keep and self.keep(m):
                self.kept.append(m)


def run_node(*args):
    # _duration: a node that wrongly starts ends by itself (1 s of simulated time)
    p = subprocess.run(["rosrun", "flex3rpr", "flex3rpr_node", "_duration:=1.0", "_realtime_factor:=0.0", *args],
                       capture_output=True, text=True, timeout=600)
    return p.returncode, p.stdout + p.stderr


class DefaultLaunch(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("default_launch_test", anonymous=True)
        cls.status = {ns: Latest(ns + "/flex3rpr_node/status", SimStatus) for ns in ("", "/posed", "/held")}
        cls.odom = {ns: Latest(ns + "/flex3rpr_node/odom", Odometry) for ns in ("", "/posed", "/held")}
        cls.log = Latest("/rosout", Log, keep=lambda m: m.name == "/held/flex3rpr_node"
                         and "no command for the period" in m.msg)
        for ns in ("", "/posed", "/held"):
            wait_for(lambda: cls.status[ns].msg is not None and cls.odom[ns].msg is not None, 300,
                     "~status and ~odom of %s/flex3rpr_node" % ns)

    def test_a_the_default_launch_is_not_singular(self):
        status, odom = self.status[""].msg, self.odom[""].msg
        self.assertLess(status.actuation_condition, 1e3)
        self.assertGreater(status.actuation_condition, 1.0)
        # nothing pushes it: it stays at the scene's pose
        self.assertAlmostEqual(odom.pose.pose.position.x, 0.0, places=9)
        self.assertAlmostEqual(odom.pose.pose.position.y, 0.0, places=9)
        self.assertAlmostEqual(yaw(odom.pose.pose.orientation), 0.3, places=9)
        self.assertFalse(any(status.outside_stroke))
        self.assertEqual(status.last_error, "")

    def test_b_initial_pose_is_honoured(self):
        odom, status = self.odom["/posed"].msg, self.status["/posed"].msg
        self.assertTrue(status.paused)
        self.assertEqual(status.sim_time, 0.0)
        self.assertAlmostEqual(odom.pose.pose.position.x, 0.01, places=12)
        self.assertAlmostEqual(odom.pose.pose.position.y, 0.005, places=12)
        self.assertAlmostEqual(yaw(odom.pose.pose.orientation), 0.2, places=12)
        self.assertLess(status.actuation_condition, 1e3)

    def test_c_a_bad_initial_pose_is_named(self):
        format_error = "is not x,y,phi: three finite numbers"
        for k, (value, extra, message) in enumerate((
                ("0.01,0.005", [], format_error),
                ("nan,0,0", [], format_error),
                ("0,0,inf", [], format_error),
                ("x,y,phi", [], format_error),
                ("0.01,0.005,0.2,0", [], format_error),
                ("2,0,0", [], "parameter ~initial_pose: initial.platform_pose[0]: 2 is out of range"),
                # rest.yaml has end stops, which refuse the pose first: a scene without them
                ("0.28,-0.16,0", ["_scene:=" + IDLE_RIGID],
                 "parameter ~initial_pose: pose (0.28, -0.16, 0) unreachable: leg 1"),
                ("0.1,0,0", ["_end_stops:=true"], "parameter ~initial_pose: pose (0.1, 0, 0) beyond the end stops"))):
            scene = [] if any(e.startswith("_scene:=") for e in extra) else ["_scene:=" + REST]
            code, out = run_node("__name:=bad_pose_%d" % k, *scene, "_initial_pose:=" + value, *extra)
            self.assertNotEqual(code, 0, value + ": " + out[-2000:])
            self.assertIn("parameter ~initial_pose", out, value + ": " + out[-2000:])
            self.assertIn(message, out, value + ": " + out[-2000:])
        # through the launch file's argument, on a master of its own
        port = free_port()
        env = dict(os.environ, ROS_MASTER_URI="http://localhost:%d/" % port)
        p = subprocess.run(["roslaunch", "-p", str(port), "flex3rpr", "sim.launch", "initial_pose:=0.01,nan,0",
                            "required:=true"], env=env, stdin=subprocess.DEVNULL, capture_output=True, text=True,
                           timeout=600)
        out = p.stdout + p.stderr
        self.assertIn("parameter ~initial_pose: '0.01,nan,0' " + format_error, out, out[-3000:])
        self.assertIn("REQUIRED process [flex3rpr_node", out, out[-3000:])

    def test_d_the_wait_warning_prints_under_simulated_time(self):
        self.assertTrue(rospy.get_param("/use_sim_time"))
        wait_for(lambda: self.log.kept, 600, "the held node's warning on /rosout")
        self.assertEqual(self.status["/held"].msg.sim_time, 0.0)
        self.assertGreater(self.status["/held"].msg.waiting_for_command, 0.0)

    def late_listener(self, prefix):
        p = subprocess.run(["/usr/bin/python3", "-c", LATE_LISTENER, prefix], capture_output=True, text=True,
                           timeout=600)
        resolved = {tuple(line.split()[1:3]): [float(v) for v in line.split()[3:]]
                    for line in p.stdout.splitlines() if line.startswith("resolved ")}
        return resolved, p.stdout + p.stderr

    def test_e_a_late_listener_resolves_a_waiting_or_paused_node(self):
        wait_for(lambda: self.status["/held"].msg.waiting_for_command > 0.0, 600, "the held node waiting")
        for prefix, pose in (("held/", (0.0, 0.0, 0.3)), ("posed/", (0.01, 0.005, 0.2))):
            resolved, out = self.late_listener(prefix)
            self.assertIn((prefix + "base", prefix + "platform"), resolved, out)
            self.assertIn(("world", prefix + "leg_2_beam_10"), resolved, out)
            x, y, phi, stamp = resolved[(prefix + "base", prefix + "platform")]
            self.assertAlmostEqual(x, pose[0], places=9)
            self.assertAlmostEqual(y, pose[1], places=9)
            self.assertAlmostEqual(phi, pose[2], places=9)
            self.assertEqual(stamp, 0)  # the state at t = 0, which the node still holds
            self.assertNotIn("TF_REPEATED_DATA", out)
        ns = "/held"
        self.assertEqual(self.status[ns].msg.sim_time, 0.0, "the held node has not stepped")


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "default_launch", DefaultLaunch)

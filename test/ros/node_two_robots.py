#!/usr/bin/env python3
"""rostest: two robots in two namespaces (two_robots.test) share only the world frame. Each
one's frames carry its prefix, each tree is complete (every frame of its URDF reaches world),
the two sets of frames are disjoint, and no frame has two publishers' data. The rviz config and
launch files name no topic absolutely but /clock and /tf."""
import glob
import math
import os
import re
import threading
import time
import unittest
import xml.etree.ElementTree as ET

import rospkg
import rospy
import rostest
import tf2_ros
from tf2_msgs.msg import TFMessage

from flex3rpr.msg import SimStatus
from wall_wait import wait_for

PKG = rospkg.RosPack().get_path("flex3rpr")


class TwoRobots(unittest.TestCase):
    def test_trees_are_disjoint_and_complete(self):
        lock = threading.Lock()
        children = {}  # child frame -> set of (parent, publisher)

        def on_tf(m):
            with lock:
                for t in m.transforms:
                    children.setdefault(t.child_frame_id, set()).add(
                        (t.header.frame_id, m._connection_header["callerid"]))
        subs = [rospy.Subscriber(topic, TFMessage, on_tf, queue_size=None) for topic in ("/tf", "/tf_static")]
        status = {}
        for robot in ("robot1", "robot2"):
            subs.append(rospy.Subscriber("/%s/flex3rpr_node/status" % robot, SimStatus,
                                         lambda m, r=robot: status.__setitem__(r, m)))
        wait_for(lambda: all(r in status and status[r].sim_time > 0.05 for r in ("robot1", "robot2")), 300,
                 "both nodes' ~status")
        links = {}
        for robot in ("robot1", "robot2"):
            root = ET.fromstring(rospy.get_param("/%s/robot_description" % robot))
            links[robot] = {l.get("name") for l in root.iter("link")}
            self.assertTrue(all(name.startswith(robot + "/") for name in links[robot]), links[robot])
        self.assertEqual(len(links["robot1"]), 3 * (3 + 5) + 5)  # base, platform, C_i; per leg 3 + 5 stations
        self.assertEqual(len(links["robot2"]), 3 * (3 + 11) + 5)
        wait_for(lambda: set(children) >= links["robot1"] | links["robot2"], 120, "every frame of both URDFs")
        with lock:
            for frame, sources in children.items():
                self.assertEqual(len({p for p, _ in sources}), 1, "%s has two parents: %s" % (frame, sources))
                self.assertEqual(len({c for _, c in sources}), 1, "%s has two publishers: %s" % (frame, sources))
            published = {robot: {f for f, s in children.items() if {c for _, c in s} == {"/%s/flex3rpr_node" % robot}}
                         for robot in ("robot1", "robot2")}
        self.assertEqual(published["robot1"], links["robot1"])
        self.assertEqual(published["robot2"], links["robot2"])
        self.assertFalse(published["robot1"] & published["robot2"])
        buf = tf2_ros.Buffer()
        tf2_ros.TransformListener(buf)
        for robot in ("robot1", "robot2"):
            for frame in links[robot]:
                wait_for(lambda: buf.can_transform("world", frame, rospy.Time(0)), 60, frame + " in world")
        # ~base_pose: robot2's base stands 1 m away, turned round; robot1's at the origin
        for robot, (x, y, yaw) in (("robot1", (0.0, 0.0, 0.0)), ("robot2", (1.0, 0.0, 3.1416))):
            b = buf.lookup_transform("world", robot + "/base", rospy.Time(0)).transform
            self.assertAlmostEqual(b.translation.x, x, delta=1e-12)
            self.assertAlmostEqual(b.translation.y, y, delta=1e-12)
            turned = 2.0 * math.atan2(b.rotation.z, b.rotation.w) - yaw  # q and -q: the same yaw
            self.assertAlmostEqual(math.atan2(math.sin(turned), math.cos(turned)), 0.0, delta=1e-12)
        # the wall clock: stamps near now, not simulated seconds since 0
        t = buf.lookup_transform("world", "robot2/platform", rospy.Time(0)).header.stamp.to_sec()
        self.assertLess(abs(t - time.time()), 3600.0)
        for s in subs:
            s.unregister()

    def test_no_absolute_topic_names(self):
        files = [PKG + "/config/flex3rpr.rviz"] + glob.glob(PKG + "/launch/*.launch")
        for path in files:
            text = open(path).read()
            # "$(arg ns)/joint_states" is a name written out from a namespace argument
            for name in re.findall(r"(?<![\w$)])/flex3rpr_node/\w+|(?<![\w$)])/joint_states", text):
                self.fail("%s names %s absolutely" % (os.path.basename(path), name))


if __name__ == "__main__":
    rospy.init_node("node_two_robots", anonymous=True)
    rostest.rosrun("flex3rpr", "node_two_robots", TwoRobots)

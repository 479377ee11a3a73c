#!/usr/bin/env python3
"""A first controller as a newcomer writes it: a PD on the leg strokes that answers every
joint_states message with one command at once, with no wait for its publisher to connect and no
stamp. Logs every state it answered (repr-exact) to the file given.

usage: naive_pd.py LOG.csv [--stamped-twice]
  --stamped-twice: each answer carries the stamp of the state it answers and goes out twice, as
  a controller that retries would send it; the node takes the first and discards the second.
  Not at t = 0: a zero stamp reads as no stamp (ROS's convention), so that answer goes once.
"""
import sys

import rospy
from flex3rpr.msg import EffortCommand
from sensor_msgs.msg import JointState

rospy.init_node("naive_pd")
log = open(sys.argv[1], "w", buffering=1)
stamped_twice = "--stamped-twice" in sys.argv[2:]
pub = rospy.Publisher("/flex3rpr_node/command", EffortCommand, queue_size=100)
target = None


def answer(js):
    global target
    pos, vel = dict(zip(js.name, js.position)), dict(zip(js.name, js.velocity))
    rho = [pos["leg_%d_prismatic" % (i + 1)] for i in range(3)]
    if target is None:  # push the first leg out 1 mm, hold the others where they start
        target = [rho[0] + 1e-3, rho[1], rho[2]]
    cmd = EffortCommand()
    cmd.leg_force = [200.0 * (target[i] - rho[i]) - 5.0 * vel["leg_%d_prismatic" % (i + 1)]
                     for i in range(3)]
    log.write("%.9f,%s\n" % (js.header.stamp.to_sec(), ",".join(repr(x) for x in js.position)))
    if stamped_twice and not js.header.stamp.is_zero():
        cmd.header.stamp = js.header.stamp
        pub.publish(cmd)
    pub.publish(cmd)


rospy.Subscriber("/joint_states", JointState, answer, queue_size=100)
rospy.spin()

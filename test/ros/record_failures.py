#!/usr/bin/env python3
"""rostest (record_failures.test): recording counts live connections, not master entries, and a
recording that fails fails the command that ran it.

test_a_a_stale_subscriber_does_not_stop_the_recording
    A master whose /joint_states lists a subscriber of a killed process (registered through the
    master's XML-RPC registerSubscriber with a URI where nothing listens). `rosrun flex3rpr
    record_bag` (record.launch) still records paper simulation 1 for 0.02 s: exit code 0, every
    state the node published on every output topic, and the node never gives up waiting for
    subscribers ("lacks subscribers"). Before, the node waited for the stale entry until
    ~subscriber_timeout and the launch ended with an empty bag and exit code 0.
test_b_a_failed_recording_fails_the_launch
    record_bag with an initial_pose beyond the end stops, which the node refuses at its start: the
    recorder holds no state and exits 1; roslaunch ends (the recorder is its required node, and
    roslaunch itself exits 0) and record_bag exits non-zero, saying why.

The time limits only catch a hang; no wall time is asserted."""
import os
import re
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import unittest
import xmlrpc.client

import rosbag
import rospkg
import rostest

PKG = rospkg.RosPack().get_path("flex3rpr")
SCENE = os.path.join(PKG, "config", "scenes", "paper_sim1.yaml")
OUTPUTS = ["/clock", "/tf", "/joint_states", "/flex3rpr_node/status", "/flex3rpr_node/beam_state",
           "/flex3rpr_node/beams", "/flex3rpr_node/odom"]
TIMEOUT = 500.0


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def stop(p):
    if p.poll() is not None:
        return
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(p.pid, sig)
            p.wait(20)
            return
        except ProcessLookupError:
            return
        except subprocess.TimeoutExpired:
            continue


def record(env, *args):
    """record_bag ARGS under env: (exit code or None on a hang, output without colours)."""
    p = subprocess.Popen(["rosrun", "flex3rpr", "record_bag", *args], env=env, stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace",
                         start_new_session=True)
    try:
        out, _ = p.communicate(timeout=TIMEOUT)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        stop(p)
        out, _ = p.communicate()
        rc = None
    return rc, re.sub(r"\x1b\[[0-9;]*m", "", out or "")


class RecordFailures(unittest.TestCase):
    def setUp(self):
        self.work = tempfile.mkdtemp(prefix="f3r_record_failures_")
        self.port = free_port()
        self.env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{self.port}/", ROS_HOSTNAME="localhost")
        self.master = subprocess.Popen(["rosmaster", "--core", "-p", str(self.port)], env=self.env,
                                       stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                       stderr=subprocess.DEVNULL, start_new_session=True)
        proxy = xmlrpc.client.ServerProxy(self.env["ROS_MASTER_URI"])
        end = time.time() + 300
        while True:
            try:
                proxy.getPid("/record_failures_test")
                break
            except OSError:
                if time.time() > end:
                    raise
                time.sleep(0.1)

    def tearDown(self):
        stop(self.master)
        shutil.rmtree(self.work, ignore_errors=True)

    def test_a_a_stale_subscriber_does_not_stop_the_recording(self):
        proxy = xmlrpc.client.ServerProxy(self.env["ROS_MASTER_URI"])
        dead = f"http://localhost:{free_port()}/"  # nothing listens there: a killed process's URI
        code, _, _ = proxy.registerSubscriber("/killed_listener", "/joint_states", "sensor_msgs/JointState", dead)
        self.assertEqual(code, 1)
        bag = os.path.join(self.work, "stale.bag")
        rc, out = record(self.env, f"scene:={SCENE}", f"bag:={bag}", "duration:=0.02")
        tail = "\n--- output (tail) ---\n" + "\n".join(out.splitlines()[-40:])
        self.assertIsNotNone(rc, "record_bag did not end" + tail)
        self.assertNotIn("lacks subscribers", out, tail)
        self.assertEqual(rc, 0, tail)
        self.assertIn("/killed_listener", str(proxy.getSystemState("/t")[2][1]), "the stale entry stayed")
        with rosbag.Bag(bag) as b:
            counts = {t: i.message_count for t, i in b.get_type_and_topic_info().topics.items()}
            last = None
            for _, msg, _ in b.read_messages(topics=["/flex3rpr_node/status"]):
                last = msg
        self.assertIsNotNone(last, tail)
        self.assertEqual(last.published_states, 21, tail)  # t = 0, 0.001, ..., 0.02
        for t in OUTPUTS:
            self.assertEqual(counts.get(t, 0), last.published_states, t + tail)

    def test_b_a_failed_recording_fails_the_launch(self):
        bag = os.path.join(self.work, "failed.bag")
        # a scene make_urdf takes (roslaunch itself fails on one it refuses), and a pose the node refuses
        rc, out = record(self.env, f"scene:={SCENE}", f"bag:={bag}", "duration:=0.02", "end_stops:=true",
                         "initial_pose:=0.1,0,0")
        tail = "\n--- output (tail) ---\n" + "\n".join(out.splitlines()[-40:])
        self.assertIsNotNone(rc, "record_bag did not end" + tail)
        self.assertNotEqual(rc, 0, tail)
        self.assertIn("parameter ~initial_pose: pose (0.1, 0, 0) beyond the end stops", out, tail)
        self.assertIn("holds no state", out, tail)
        self.assertIn("record_bag: the recording failed", out, tail)


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "record_failures", RecordFailures)

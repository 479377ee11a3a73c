#!/usr/bin/env python3
"""rostest (record_lockstep.test): a recording through launch/record.launch keeps every period,
however busy the machine, and ends cleanly.

One recording of paper simulation 1 (0.05 s at 1 kHz: 51 states) with `roslaunch flex3rpr
record.launch` (its own master on a free port), while one CPU hog per core (busy Python loops)
competes with the node and the recorder (nodes/record_lockstep). record.launch holds the node
in lockstep with the recorder, so the load may slow the recording but not thin it:

test_launch_ends_cleanly       roslaunch exits with code 0, without "REQUIRED process has died"
                               (the recorder, the required node, ends the launch after closing the
                               bag), and the bag is closed (no BAG.active).
test_every_period_on_every_output_topic
                               every output topic (/clock, /tf, joint_states, ~status, ~beam_state,
                               ~beams, ~odom) holds exactly as many messages as the node says it
                               published (the last ~status.published_states in the bag), one per
                               stamp, the same stamps as ~status; the last state is at the
                               duration; /tf_static holds one message.
test_acknowledgements_are_not_recorded
                               nobody else sent a command, so the command topics hold nothing: the
                               recorder's own answers on ~command are not in the bag.

Nothing depends on the machine's speed: the time limits only catch a hang (the node under a
sanitizer on a loaded 2-core machine is slow), and no wall time is asserted. F3R_NODE_LAUNCH_PREFIX
is passed to record.launch's launch_prefix, as the render test does."""
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

import rosbag
import rospkg
import rospy
import rostest

PKG = rospkg.RosPack().get_path("flex3rpr")
SCENE = os.path.join(PKG, "config", "scenes", "paper_sim1.yaml")
DURATION, RATE = 0.05, 1000
OUTPUTS = ["/clock", "/tf", "/joint_states", "/flex3rpr_node/status", "/flex3rpr_node/beam_state",
           "/flex3rpr_node/beams", "/flex3rpr_node/odom"]
COMMANDS = ["/flex3rpr_node/command", "/flex3rpr_node/effort_group/command", "/flex3rpr_node/platform_wrench"]
LAUNCH_TIMEOUT = 800.0  # s; the rostest time limit is 900


def free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def stamp_of(topic, msg):
    if topic == "/clock":
        return msg.clock
    if topic in ("/tf", "/tf_static"):
        return msg.transforms[0].header.stamp if msg.transforms else None
    if hasattr(msg, "markers"):
        return msg.markers[0].header.stamp if msg.markers else None
    return msg.header.stamp


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


class RecordLockstep(unittest.TestCase):
    # A port free_port() found free may be taken before roslaunch binds it: another test running
    # beside this one can pick the same port for its own master (seen once in CI: "run_id on
    # parameter server does not match"). The launch then never starts, and a new port is tried.
    PORT_TAKEN = ("run_id on parameter server does not match", "roscore cannot run as another",
                  "Address already in use")

    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="f3r_record_lockstep_")
        cls.bag = os.path.join(cls.work, "paper_sim1.bag")
        for attempt in range(3):
            cls.record()
            if cls.rc == 0 or not any(text in cls.output for text in cls.PORT_TAKEN):
                return
            print("the master's port was taken (attempt %d): another port" % (attempt + 1), flush=True)

    @classmethod
    def record(cls):
        env = dict(os.environ)
        port = free_port()
        env["ROS_MASTER_URI"] = f"http://localhost:{port}/"
        env["ROS_HOSTNAME"] = "localhost"
        cmd = ["roslaunch", "-p", str(port), "flex3rpr", "record.launch", f"scene:={SCENE}", f"bag:={cls.bag}",
               f"duration:={DURATION}", f"publish_rate:={RATE}"]
        if os.environ.get("F3R_NODE_LAUNCH_PREFIX"):
            cmd.append("launch_prefix:=" + os.environ["F3R_NODE_LAUNCH_PREFIX"])
        hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"], stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
                for _ in range(os.cpu_count() or 2)]
        launch = None
        try:
            t0 = time.time()
            launch = subprocess.Popen(cmd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, text=True, errors="replace", start_new_session=True)
            try:
                out, _ = launch.communicate(timeout=LAUNCH_TIMEOUT)
                cls.rc = launch.returncode
            except subprocess.TimeoutExpired:
                stop(launch)
                out, _ = launch.communicate()
                cls.rc = None
            cls.output = re.sub(r"\x1b\[[0-9;]*m", "", out or "")
            print(f"recorded in {time.time() - t0:.1f} s with {len(hogs)} CPU hogs (roslaunch exit {cls.rc})",
                  flush=True)
        finally:
            for h in hogs:
                stop(h)
            if launch is not None:
                stop(launch)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def tail(self):
        return "\n--- roslaunch output (tail) ---\n" + "\n".join(self.output.splitlines()[-40:])

    def read_bag(self):
        if not os.path.isfile(self.bag):
            self.fail(f"no bag {self.bag}" + (" (only .active: not closed)" if os.path.exists(self.bag + ".active")
                                             else "") + self.tail())
        stamps, counts, last_status = {}, {}, None
        with rosbag.Bag(self.bag) as bag:
            for topic, info in bag.get_type_and_topic_info().topics.items():
                counts[topic] = info.message_count
            for topic, msg, _ in bag.read_messages():
                st = stamp_of(topic, msg)
                stamps.setdefault(topic, []).append(None if st is None else st.to_nsec())
                if topic == "/flex3rpr_node/status":
                    last_status = msg
        return counts, stamps, last_status

    def test_launch_ends_cleanly(self):
        self.assertIsNotNone(self.rc, f"roslaunch did not end within {LAUNCH_TIMEOUT} s" + self.tail())
        self.assertNotIn("REQUIRED process", self.output, self.tail())
        self.assertEqual(self.rc, 0, self.tail())
        self.assertFalse(os.path.exists(self.bag + ".active"), "the bag was not closed" + self.tail())
        self.assertTrue(os.path.isfile(self.bag), "no bag" + self.tail())

    def test_every_period_on_every_output_topic(self):
        counts, stamps, status = self.read_bag()
        self.assertIsNotNone(status, "no ~status in the bag" + self.tail())
        published = status.published_states
        short = {t: counts.get(t, 0) for t in OUTPUTS if counts.get(t, 0) != published}
        self.assertFalse(short, f"topic: messages, where the node published {published} states "
                                f"(the last ~status.published_states): {short}" + self.tail())
        want = stamps["/flex3rpr_node/status"]
        self.assertEqual(len(set(want)), len(want), "~status repeats a stamp")
        for t in OUTPUTS:
            self.assertEqual(sorted(stamps[t]), sorted(want), f"{t} holds other stamps than ~status")
        self.assertEqual(counts.get("/tf_static", 0), 1, "/tf_static")
        self.assertAlmostEqual(status.sim_time, DURATION, delta=0.5 / RATE,
                               msg="the last state in the bag is not at the duration")
        self.assertGreater(published, 1)

    def test_acknowledgements_are_not_recorded(self):
        counts, _, _ = self.read_bag()
        sent = {t: counts[t] for t in COMMANDS if counts.get(t, 0)}
        self.assertFalse(sent, f"command topics hold messages though nobody else sent one: {sent}")
        self.assertIn("record_lockstep: wrote", self.output, self.tail())


if __name__ == "__main__":
    rospy.init_node("record_lockstep_test", anonymous=True)
    rostest.rosrun("flex3rpr", "record_lockstep", RecordLockstep)

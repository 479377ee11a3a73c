#!/usr/bin/env python3
"""rostest (flood.test): bad input never corrupts a run.

Two nodes, one per phase (launched by flood.test):
  /flood/flex3rpr_node   rigid links with joint friction (test/scenes/flood_damped_rigid.yaml),
                         paced to the wall clock (realtime_factor 1), 1 kHz publishing, world
                         frame 'flood_world';
  /replay/flex3rpr_node  fixed-pinned links (r = 3) at rest, driven one period at a time.

test_a_flood: a separate process (this script with --flood: its busy loop would otherwise hold
this process's interpreter lock) publishes 10,000 random commands at up to 10 kHz, valid and
invalid mixed, on ~command, ~effort_group/command and ~platform_wrench (the topics in shuffled
blocks of three; the last three set every force to zero). The node must stay up (integrating, no
error, registered, the platform at rest again), publish every period (its own count,
~status.published_states, equals sim_time * publish_rate + 1 in every status), and
~status.rejected_commands must rise by exactly the number of invalid commands sent: fewer means
that ROS dropped commands in the node's subscriber queues (flood.test makes them deep enough to
hold the whole flood, ~command_queue_size), more that a valid command was rejected.

Nothing here depends on how fast the machine is: no wall-clock rate, real-time factor or count of
messages this process happened to receive is asserted (a loaded machine under a sanitizer may
run the node far slower than the wall clock). The rates reached are logged; bench/node_speed
measures them.

test_b_replay: the replay node is paused and reset, then advanced with ~step one publish period
at a time; before each step one command (valid and changing one force, valid and changing
nothing, or invalid) is published, a valid one followed by an invalid probe on the same topic.
The ~status published after the step must count the probe as rejected, which proves that the
command was taken before the step, so each command's effect time is known exactly. Every
period's joint positions, rates and efforts and the final modal state and platform pose must
equal the CLI's (flex3rpr_sim --stop-at-outputs --hold T:I:V for each change of the summed
forces, the valid commands alone) to 1e-9.

Seeds: F3R_FLOOD_SEED (default random, printed on failure), F3R_REPLAY_SEED (default fixed).
"""
import csv
import json
import math
import os
import random
import subprocess
import sys
import tempfile
import threading
import time
import unittest
import warnings

N_FLOOD = 10000
FLOOD_RATE = 10000.0          # commands per second of wall time
PUBLISH_RATE = 1000.0         # the nodes' ~publish_rate (flood.test)
PERIOD = 1.0 / PUBLISH_RATE
FLOOD_WORLD = "flood_world"   # the flood node's ~world_frame (flood.test); its other frames are flood/...
REPLAY_STEPS = 240
CLI_MAX_HOLDS = 64            # MAX_HOLDS of src/cli/flex3rpr_sim.c
REPLAY_CHANGES = 60           # valid commands that change a force: one --hold each
N_MODAL = 9                   # idle_fixed_pinned.yaml: three links of 3 modes
LIMIT_FORCE, LIMIT_TORQUE = 1000.0, 100.0


# --- commands ------------------------------------------------------------------------------------
# A command is (topic, fields, valid); topic 0 ~command, 1 ~effort_group/command, 2
# ~platform_wrench. fields is a plain dict, turned into a message by to_message().

def random_invalid(rng, topic, n_modal, world):
    """A command the node must reject, of one of the kinds docs/ros.md's "Inputs" lists."""
    bad = rng.choice([math.nan, -math.nan, math.inf, -math.inf])
    if topic == 0:
        c = {"leg_force": [0.0] * 3, "cylinder_torque": [0.0] * 3, "platform": [0.0] * 3, "modal": []}
        kind = rng.randrange(4)
        if kind == 0:    # NaN or Inf somewhere
            field = rng.choice(["leg_force", "cylinder_torque", "platform"])
            c[field][rng.randrange(3)] = bad
        elif kind == 1:  # modal of the wrong length
            c["modal"] = [rng.uniform(-1, 1) for _ in range(rng.choice(
                [k for k in range(1, 2 * N_MODAL + 2) if k != n_modal]))]
        elif kind == 2:  # above the limit
            if rng.random() < 0.5:
                c["leg_force"][rng.randrange(3)] = rng.choice([-1, 1]) * LIMIT_FORCE * rng.uniform(1.000001, 1e3)
            else:
                c["cylinder_torque"][rng.randrange(3)] = rng.choice([-1, 1]) * LIMIT_TORQUE * rng.uniform(1.000001, 1e3)
        else:            # a bad modal value, or a bad value after valid ones
            if n_modal:
                c["modal"] = [0.0] * n_modal
                c["modal"][rng.randrange(n_modal)] = rng.choice([bad, 1e9])
            else:
                c["platform"][2] = rng.choice([bad, -LIMIT_TORQUE * 1.5])
        return (0, c, False)
    if topic == 1:
        kind = rng.randrange(3)
        if kind == 0:
            data = [rng.uniform(-1, 1) for _ in range(rng.choice([0, 1, 2, 3, 4, 5, 7, 8, 12]))]
        else:
            data = [0.0] * 6
            k = rng.randrange(6)
            data[k] = bad if kind == 1 else rng.choice([-1, 1]) * (LIMIT_FORCE if k < 3 else LIMIT_TORQUE) * 1.01
        return (1, {"data": data}, False)
    w = {"frame": world, "force": [0.0, 0.0, 0.0], "torque": [0.0, 0.0, 0.0]}
    kind = rng.randrange(4)
    if kind == 0:
        # frames tf2 does not know (the replay node's world, base and platform_c1 it does)
        w["frame"] = rng.choice(["moon", "World", world + " ", "flood/platform_c0", "leg_4_piston",
                                 "/" + world, "pl\u00e4tform"])
        w["force"][0] = 1.0
    elif kind == 1:
        w["force" if rng.random() < 0.5 else "torque"][rng.randrange(3)] = bad
    elif kind == 2:  # out of the plane
        if rng.random() < 0.5:
            w["force"][2] = rng.uniform(0.1, 1.0)
        else:
            w["torque"][rng.randrange(2)] = rng.uniform(0.1, 1.0)
    else:
        w["torque"][2] = rng.choice([-1, 1]) * LIMIT_TORQUE * rng.uniform(1.01, 10)
    return (2, w, False)


def random_valid_flood(rng, topic):
    """A small valid command for the rigid flood node (no modal coordinates)."""
    if topic == 0:
        return (0, {"leg_force": [rng.uniform(-1, 1) for _ in range(3)],
                    "cylinder_torque": [rng.uniform(-0.05, 0.05) for _ in range(3)],
                    "platform": [rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-0.01, 0.01)],
                    "modal": []}, True)
    if topic == 1:
        return (1, {"data": [rng.uniform(-1, 1) for _ in range(3)] +
                            [rng.uniform(-0.05, 0.05) for _ in range(3)]}, True)
    return (2, {"frame": rng.choice([FLOOD_WORLD, "", "flood/platform"]),
                "force": [rng.uniform(-1, 1), rng.uniform(-1, 1), rng.choice([0.0, -0.0])],
                "torque": [0.0, 0.0, rng.uniform(-0.01, 0.01)]}, True)


ZERO_COMMANDS = [(0, {"leg_force": [0.0] * 3, "cylinder_torque": [0.0] * 3, "platform": [0.0] * 3,
                      "modal": []}, True),
                 (1, {"data": [0.0] * 6}, True),
                 (2, {"frame": "", "force": [0.0] * 3, "torque": [0.0] * 3}, True)]


def flood_commands(seed):
    """N_FLOOD commands, about half invalid, the topics in shuffled blocks of three; the last
    three (valid) set every topic's force to zero, so that the platform comes to rest."""
    rng = random.Random(seed)
    commands = []
    while len(commands) < N_FLOOD - 3:
        for topic in rng.sample(range(3), 3):
            if rng.random() < 0.5:
                commands.append(random_valid_flood(rng, topic))
            else:
                commands.append(random_invalid(rng, topic, 0, FLOOD_WORLD))
    return commands[:N_FLOOD - 3] + ZERO_COMMANDS


def to_message(topic, fields):
    from flex3rpr.msg import EffortCommand
    from geometry_msgs.msg import WrenchStamped
    from std_msgs.msg import Float64MultiArray
    if topic == 0:
        return EffortCommand(leg_force=fields["leg_force"], cylinder_torque=fields["cylinder_torque"],
                             platform=fields["platform"], modal=fields["modal"])
    if topic == 1:
        return Float64MultiArray(data=fields["data"])
    m = WrenchStamped()
    m.header.frame_id = fields["frame"]
    m.wrench.force.x, m.wrench.force.y, m.wrench.force.z = fields["force"]
    m.wrench.torque.x, m.wrench.torque.y, m.wrench.torque.z = fields["torque"]
    return m


def publishers(node):
    import rospy
    from flex3rpr.msg import EffortCommand
    from geometry_msgs.msg import WrenchStamped
    from std_msgs.msg import Float64MultiArray
    with warnings.catch_warnings():  # queue_size=None: publish() writes before it returns
        warnings.simplefilter("ignore")
        return [rospy.Publisher(node + "/command", EffortCommand, queue_size=None, tcp_nodelay=True),
                rospy.Publisher(node + "/effort_group/command", Float64MultiArray, queue_size=None,
                                tcp_nodelay=True),
                rospy.Publisher(node + "/platform_wrench", WrenchStamped, queue_size=None,
                                tcp_nodelay=True)]


def flood_main(seed, node):
    """The flooding process: prints one JSON line with what it sent and when."""
    import rospy
    rospy.init_node("flooder", anonymous=True, disable_signals=True)
    pubs = publishers(node)
    commands = flood_commands(seed)
    messages = [(pubs[t], to_message(t, f)) for t, f, _ in commands]
    end = time.time() + 30
    while time.time() < end and not all(p.get_num_connections() > 0 for p in pubs):
        time.sleep(0.01)
    time.sleep(0.5)  # let the node's side of the connections settle
    gap = 1.0 / FLOOD_RATE
    max_lag = 0.05  # after this process was descheduled, catch up by at most 50 ms of commands
    wall0 = time.time()
    start = time.perf_counter()
    target = start
    for pub, msg in messages:
        while time.perf_counter() < target:  # a busy wait: sleeping cannot keep 100 us steps
            pass
        if time.perf_counter() - target > max_lag:
            target = time.perf_counter() - max_lag
        pub.publish(msg)  # synchronous (queue_size=None): on the wire when it returns
        target += gap
    elapsed = time.perf_counter() - start
    print(json.dumps({
        "seed": seed, "sent": len(commands), "invalid": sum(1 for c in commands if not c[2]),
        "per_topic": [sum(1 for c in commands if c[0] == t) for t in range(3)],
        "wall_start": wall0, "wall_end": wall0 + elapsed, "rate": len(commands) / elapsed}))
    sys.stdout.flush()
    time.sleep(0.5)  # keep the connections open while the node takes the last commands
    rospy.signal_shutdown("done")


# --- the test ------------------------------------------------------------------------------------
if __name__ == "__main__" and len(sys.argv) > 1 and sys.argv[1] == "--flood":
    flood_main(int(sys.argv[2]), sys.argv[3])
    sys.exit(0)

import rosgraph          # noqa: E402
import rospkg            # noqa: E402
import rospy             # noqa: E402
import rostest           # noqa: E402
from sensor_msgs.msg import JointState         # noqa: E402
from std_srvs.srv import Empty, Trigger        # noqa: E402
from tf2_msgs.msg import TFMessage             # noqa: E402

from flex3rpr.msg import BeamState, SimStatus  # noqa: E402
import wall_wait

FLOOD = "/flood/flex3rpr_node"
REPLAY = "/replay/flex3rpr_node"
PKG = rospkg.RosPack().get_path("flex3rpr")


def wait_for(predicate, timeout, what):
    wall_wait.wait_for(predicate, timeout, what, poll=0.002)  # the flood's timing is tight


class Watch:
    """What a node publishes, with wall arrival times: joint_states, and optionally its status
    and beam state."""

    def __init__(self, node, joint_topic, everything):
        self.lock = threading.Lock()
        self.statuses = []   # (wall, SimStatus)
        self.joints = []     # (wall, JointState)
        self.beams = []      # BeamState
        self.subs = [rospy.Subscriber(joint_topic, JointState, self._joints, queue_size=None)]
        if everything:
            self.subs += [rospy.Subscriber(node + "/status", SimStatus, self._status, queue_size=None),
                          rospy.Subscriber(node + "/beam_state", BeamState, self._beams, queue_size=None)]

    def _status(self, m):
        with self.lock:
            self.statuses.append((time.time(), m))

    def _joints(self, m):
        with self.lock:
            self.joints.append((time.time(), m))

    def _beams(self, m):
        with self.lock:
            self.beams.append(m)

    def last_status(self):
        with self.lock:
            return self.statuses[-1][1] if self.statuses else None

    def clear(self):
        with self.lock:
            self.statuses.clear()
            self.joints.clear()
            self.beams.clear()


def one_status(node, timeout=60.0):
    return rospy.wait_for_message(node + "/status", SimStatus, timeout=timeout)


class NodeFlood(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("node_flood", anonymous=True)
        for node in (FLOOD, REPLAY):
            for name in ("pause", "resume", "reset", "step"):
                rospy.wait_for_service(node + "/" + name, timeout=60)
        # While the flood runs this process takes only the flood node's joint_states (1 kHz).
        cls.flood = Watch(FLOOD, "/flood/joint_states", everything=False)
        cls.replay = Watch(REPLAY, "/replay/joint_states", everything=True)
        wait_for(lambda: cls.replay.last_status() is not None, 60, "the replay node's status")
        rospy.ServiceProxy(REPLAY + "/pause", Empty)()  # it waits, paused, for its test

    # --- flood ---
    def test_a_flood(self):
        try:
            self.flood_and_check()
        finally:  # frees the CPU for the replay
            rospy.ServiceProxy(FLOOD + "/pause", Empty)()

    def flood_and_check(self):
        seed = int(os.environ.get("F3R_FLOOD_SEED", random.SystemRandom().randrange(1 << 30)))
        before = one_status(FLOOD)
        wait_for(lambda: len(self.flood.joints) > 100, 120, "the flood node's joint_states")
        flooder = subprocess.run([sys.executable, os.path.abspath(__file__), "--flood", str(seed), FLOOD],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=90)
        report = None
        for line in flooder.stdout.splitlines():
            if line.startswith("{"):
                report = json.loads(line)
        self.assertIsNotNone(report, "the flooder (seed %d) reported nothing: %s"
                             % (seed, flooder.stderr[-3000:]))
        rospy.loginfo("flood: %s", report)

        # Stays up: still integrating and publishing, no error, still known to the master. The
        # friction stops the platform within about 15 ms of simulated time after the last
        # (zero) commands; 0.1 s of simulated time is waited for, however long it takes.
        after = one_status(FLOOD)
        latest = [after]

        def integrated_on():
            latest[0] = one_status(FLOOD, timeout=60.0)
            return latest[0].sim_time > after.sim_time + 0.1
        wait_for(integrated_on, 300, "the flood node to integrate 0.1 s on")
        status = latest[0]
        self.assertEqual(status.last_error, "")
        self.assertFalse(status.paused)
        for name in ("kinetic_energy", "potential_energy", "external_work", "energy_balance_error"):
            self.assertTrue(math.isfinite(getattr(status, name)), name)
        self.assertLess(status.constraint_residual, 1e-8)
        # Its joint_states reach that time too. Waited for, not taken from the next message: the
        # publishing may trail the status's time by a few periods on a loaded machine (a CI run
        # saw 2.827 s arrive when the status had passed 2.83 s).
        def published_on():
            with self.flood.lock:
                return self.flood.joints and \
                    self.flood.joints[-1][1].header.stamp.to_sec() > after.sim_time + 0.1 - 1e-9
        wait_for(published_on, 120, "the flood node's joint_states past %g s" % (after.sim_time + 0.1))
        with self.flood.lock:
            last = self.flood.joints[-1][1]
        self.assertLess(max(abs(v) for v in last.velocity), 1e-4, "the platform is still moving")
        self.assertTrue(rosgraph.Master(rospy.get_name()).lookupNode(FLOOD).startswith("http"))

        # Sent: all 10,000 commands (at whatever rate this machine allowed).
        self.assertEqual(report["sent"], N_FLOOD)

        # Every period published, by the node's own count: its initial state and one per period
        # of simulated time, in every status seen before, during and after the flood.
        for s in (before, after, status):
            self.assertEqual(s.published_states, int(round(s.sim_time * PUBLISH_RATE)) + 1,
                             "published_states %d at t = %.4f s" % (s.published_states, s.sim_time))

        # Only the invalid commands were rejected, and every one of them.
        rejected = status.rejected_commands - before.rejected_commands
        self.assertEqual(rejected, report["invalid"], "the node rejected %d commands; %d of those sent "
                         "were invalid (seed %d): %s" % (
                             rejected, report["invalid"], seed,
                             "ROS dropped commands in the node's subscriber queues" if rejected < report["invalid"]
                             else "valid commands were rejected"))
        # Logged, never asserted: how fast this machine ran the flood (bench/node_speed measures).
        w0, w1 = report["wall_start"], report["wall_end"]
        with self.flood.lock:
            during = [(w, m.header.stamp.to_sec()) for w, m in self.flood.joints if w0 <= w <= w1]
        sim_span = during[-1][1] - during[0][1] if len(during) > 1 else 0.0
        rospy.loginfo("flood: %d commands at %.0f/s, %d invalid, all rejected; %d periods published by "
                      "the node; %.3f s simulated during %.3f s of flood", N_FLOOD, report["rate"],
                      rejected, status.published_states, sim_span, w1 - w0)

    # --- replay ---
    def test_b_replay(self):
        rng = random.Random(int(os.environ.get("F3R_REPLAY_SEED", "20261122")))
        pause = rospy.ServiceProxy(REPLAY + "/pause", Empty)
        reset = rospy.ServiceProxy(REPLAY + "/reset", Trigger)
        step = rospy.ServiceProxy(REPLAY + "/step", Trigger, persistent=True)
        pubs = publishers(REPLAY)
        wait_for(lambda: all(p.get_num_connections() > 0 for p in pubs), 60, "replay subscriptions")
        platform = {}
        tf_lock = threading.Lock()

        def on_tf(m):
            for t in m.transforms:
                if t.child_frame_id == "platform" and t.header.frame_id == "base":
                    q = t.transform.rotation
                    with tf_lock:
                        platform[round(t.header.stamp.to_sec(), 9)] = (
                            t.transform.translation.x, t.transform.translation.y,
                            2.0 * math.atan2(q.z, q.w))
        tf_sub = rospy.Subscriber("/tf", TFMessage, on_tf, queue_size=None)
        wait_for(lambda: tf_sub.get_num_connections() > 0, 60, "the /tf subscription")

        pause()
        reset()
        wait_for(lambda: self.replay.last_status() is not None and self.replay.last_status().sim_time == 0.0
                 and self.replay.last_status().paused, 60, "the replay node reset to t = 0")
        time.sleep(0.2)
        self.replay.clear()
        wait_for(lambda: self.replay.last_status() is not None, 60, "a paused status")
        rejected0 = self.replay.last_status().rejected_commands

        plan = self.replay_plan(rng)
        held = [[0.0] * (9 + N_MODAL) for _ in range(3)]  # what each topic holds, as the node
        total = [0.0] * (9 + N_MODAL)
        holds = []          # (step, index, value) for the CLI
        applied = []        # the summed forces over each period
        invalid = 0
        for k, (topic, fields, valid, new_held) in enumerate(plan):
            pubs[topic].publish(to_message(topic, fields))
            if valid:
                held[topic] = new_held
                probe = random_invalid(rng, topic, N_MODAL, "world")
                pubs[topic].publish(to_message(topic, probe[1]))
            invalid += 1  # the command itself or its probe
            # The paused node counts the probe (or the invalid command) before the step is asked
            # for: a command and a service call travel on two connections, whose order the node's
            # network thread need not keep when this machine is busy. The probe follows the
            # command on the same connection, so once it is counted the command was taken.
            wait_for(lambda: self.replay.last_status().rejected_commands - rejected0 == invalid, 60,
                     "step %d: the node to take the command" % (k + 1))
            before = len(self.replay.statuses)
            self.assertTrue(step().success)
            t_expected = (k + 1) * PERIOD
            wait_for(lambda: any(abs(s.sim_time - t_expected) < 1e-9
                                 for _, s in self.replay.statuses[before:]), 60,
                     "step %d" % (k + 1))
            with self.replay.lock:
                first = next(s for _, s in self.replay.statuses[before:]
                             if abs(s.sim_time - t_expected) < 1e-9)
            self.assertEqual(first.rejected_commands - rejected0, invalid,
                             "step %d: a command arrived during the step (rejected %d, expected %d)"
                             % (k + 1, first.rejected_commands - rejected0, invalid))
            self.assertEqual(first.published_states, k + 2, "step %d: the node's published_states" % (k + 1))
            # The node's sum, in its order: ~command, then ~effort_group, then ~platform_wrench.
            new_total = [((0.0 + held[0][n]) + held[1][n]) + held[2][n] for n in range(9 + N_MODAL)]
            for n in range(9 + N_MODAL):
                if new_total[n] != total[n]:
                    holds.append((k, n, new_total[n]))
            total = new_total
            applied.append(list(total))
        # Every step's outputs reach this process in the end (stepped one at a time, they never
        # overflow a queue); the last of them may still be on their way.
        n_last = len(plan)
        last_stamp = n_last * PERIOD

        def last_outputs_arrived():
            with self.replay.lock:
                have = (any(abs(m.header.stamp.to_sec() - last_stamp) < 1e-9 for _, m in self.replay.joints)
                        and any(abs(m.header.stamp.to_sec() - last_stamp) < 1e-9 for m in self.replay.beams))
            with tf_lock:
                return have and round(last_stamp, 9) in platform
        wait_for(last_outputs_arrived, 60, "the last step's joint_states, beam_state and /tf")
        tf_sub.unregister()
        self.assertLessEqual(len(holds), CLI_MAX_HOLDS)
        self.assertGreaterEqual(len(holds), REPLAY_CHANGES // 2)
        n_steps = len(plan)
        t_end = n_steps * PERIOD

        # The CLI replays the changes of the summed forces alone.
        out = os.path.join(tempfile.mkdtemp(), "replay.csv")
        cli = os.path.join(os.environ.get("F3R_DEVEL", ""), "lib/flex3rpr/flex3rpr_sim")
        if not os.path.exists(cli):
            cli = subprocess.check_output(["catkin_find", "--first-only", "flex3rpr", "flex3rpr_sim"],
                                          text=True).strip()
        args = [cli, os.path.join(PKG, "test/scenes/idle_fixed_pinned.yaml"), "--stop-at-outputs",
                "--output-step", repr(PERIOD), "--duration", repr(t_end), "--out", out]
        for k, n, v in holds:
            args += ["--hold", "%r:%d:%r" % (k * PERIOD, n, v)]
        subprocess.check_call(args, stdout=subprocess.DEVNULL)
        with open(out) as f:
            rows = {int(round(float(r["t"]) / PERIOD)): r for r in csv.DictReader(f)}
        self.assertTrue(n_steps in rows, "the CLI's CSV ends before step %d" % n_steps)

        # Every period: joint positions, rates and the effort applied over the period.
        with self.replay.lock:
            joints = {int(round(m.header.stamp.to_sec() / PERIOD)): m for _, m in self.replay.joints}
            beams = {int(round(m.header.stamp.to_sec() / PERIOD)): m for m in self.replay.beams}
        with tf_lock:
            poses = {int(round(t / PERIOD)): p for t, p in platform.items()}
        worst = [0.0, ""]

        def near(node_value, cli_value, what):
            d = abs(node_value - cli_value)
            if d > worst[0]:
                worst[:] = [d, what]
            self.assertLess(d, 1e-9, "%s: node %.15g, CLI %.15g" % (what, node_value, cli_value))

        for k in range(1, n_steps + 1):
            self.assertTrue(k in joints, "no joint_states for step %d" % k)
            m, row = joints[k], rows[k]
            for j, name in enumerate(m.name):
                i = int(name.split("_")[1])
                coord = ("rho_%d" if name.endswith("prismatic") else "theta_%d") % i
                index = (i - 1) + (0 if name.endswith("prismatic") else 3)
                near(m.position[j], float(row[coord]), "%s at step %d" % (coord, k))
                near(m.velocity[j], float(row[coord + "_dot"]), "%s_dot at step %d" % (coord, k))
                self.assertEqual(m.effort[j], applied[k - 1][index], "%s effort at step %d" % (coord, k))
        # The final state: modal coordinates and rates, platform pose.
        self.assertTrue(n_steps in beams, "no beam_state for the last step")
        self.assertTrue(n_steps in poses, "no platform pose in /tf for the last step")
        b, row = beams[n_steps], rows[n_steps]
        names = ["eta_%d_%d" % (i, j) for i in (1, 2, 3) for j in (1, 2, 3)]
        for n, name in enumerate(names):
            near(b.modal[n], float(row[name]), name)
            near(b.modal_rate[n], float(row[name + "_dot"]), name + "_dot")
        for value, name in zip(poses[n_steps], ("x_p", "y_p", "phi_p")):
            near(value, float(row[name]), name)
        # The forces did move the platform: the comparison is not between two resting states.
        self.assertGreater(math.hypot(float(row["x_p"]), float(row["y_p"])), 1e-3)
        rospy.loginfo("replay: %d steps, %d valid commands (%d force changes), %d invalid and probes "
                      "rejected; final P (%.9f, %.9f) m, phi_p %.9f rad; largest difference from the "
                      "CLI %.2g (%s)", n_steps, sum(1 for c in plan if c[2]), len(holds), invalid,
                      float(row["x_p"]), float(row["y_p"]), float(row["phi_p"]), worst[0], worst[1])

    def replay_plan(self, rng):
        """REPLAY_STEPS commands: REPLAY_CHANGES valid ones that change one force, as many valid
        ones that change nothing, the rest invalid. Each entry: (topic, fields, valid, held)."""
        kinds = (["change"] * REPLAY_CHANGES + ["same"] * REPLAY_CHANGES +
                 ["invalid"] * (REPLAY_STEPS - 2 * REPLAY_CHANGES))
        rng.shuffle(kinds)
        size = 9 + N_MODAL
        held = [[0.0] * size for _ in range(3)]
        plan = []
        for kind in kinds:
            topic = rng.randrange(3)
            if kind == "invalid":
                plan.append(random_invalid(rng, topic, N_MODAL, "world") + (None,))
                continue
            h = list(held[topic])
            if kind == "change":
                n = rng.choice([range(size), range(6), [6, 7, 8]][topic])
                h[n] = self.small_force(rng, n)
            held[topic] = h
            plan.append((topic, self.fields_for(rng, topic, h), True, h))
        return plan

    @staticmethod
    def small_force(rng, n):
        """A force that keeps the platform near home over the replay: N, N m, modal N."""
        if n < 3 or n in (6, 7):
            return rng.uniform(-0.5, 0.5)
        if n < 6:
            return rng.uniform(-0.02, 0.02)
        if n == 8:
            return rng.uniform(-0.002, 0.002)
        return rng.uniform(-0.5, 0.5)

    @staticmethod
    def fields_for(rng, topic, h):
        """A valid message that makes the topic hold h (in a randomly chosen equivalent form)."""
        if topic == 0:
            modal = h[9:]
            if not any(modal) and rng.random() < 0.5:
                modal = []
            return {"leg_force": h[0:3], "cylinder_torque": h[3:6], "platform": h[6:9], "modal": modal}
        if topic == 1:
            return {"data": h[0:6]}
        # The platform frame is exact only without an in-plane force (the node turns it by the
        # simulated phi_p, which the test does not know to the bit).
        frames = ["world", ""] + (["platform"] if h[6] == 0.0 and h[7] == 0.0 else [])
        return {"frame": rng.choice(frames), "force": [h[6], h[7], 0.0], "torque": [0.0, 0.0, h[8]]}


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "node_flood", NodeFlood)

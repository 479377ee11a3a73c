#!/usr/bin/env python3
"""rostest: the node refuses a bad scene and a mismatching URDF with the error named, and runs
with no arguments at all."""
import subprocess
import time
import unittest
import xml.etree.ElementTree as ET

import rosgraph
import rospkg
import rospy
import rostest

PKG = rospkg.RosPack().get_path("flex3rpr")


def wait_until(predicate, timeout=600):
    """True once predicate holds; the bound only catches a hang."""
    end = time.time() + timeout
    while time.time() < end and not predicate():
        time.sleep(0.05)
    return predicate()


def run_node(*args, timeout=300):
    p = subprocess.run(["rosrun", "flex3rpr", "flex3rpr_node", *args], capture_output=True,
                       text=True, timeout=timeout)
    return p.returncode, p.stdout + p.stderr


class NodeStartup(unittest.TestCase):
    def test_bad_scene_exits_with_the_field_named(self):
        path = PKG + "/test/scenes/bad_modes.yaml"
        code, out = run_node("__name:=bad_scene", "_scene:=" + path)
        self.assertNotEqual(code, 0)
        self.assertIn(path + ":3: links[1].modes: 25 is out of range 1..20", out)

    def test_bad_parameter_exits_with_its_name(self):
        code, out = run_node("__name:=bad_rate", "_publish_rate:=-5.0")
        self.assertNotEqual(code, 0)
        self.assertIn("~publish_rate", out)

    def test_parameters_of_the_wrong_type_are_named(self):
        for name, value, kind in (("realtime_factor", "abc", "a number"), ("beam_points", "2.5", "an integer"),
                                  ("rtol", "tight", "a number")):
            code, out = run_node("__name:=bad_type_" + name, "_%s:=%s" % (name, value))
            self.assertNotEqual(code, 0, out[-2000:])
            self.assertIn("parameter ~%s: not %s" % (name, kind), out)

    def test_values_out_of_range_are_named_by_their_parameter(self):
        for name, value, message in (
                ("rtol", "0.5", "parameter ~rtol: solver.rtol: 0.5 is out of range"),
                ("atol", "-1.0", "parameter ~atol: solver.atol: -1 is out of range"),
                ("world_frame", "/world", "parameter ~world_frame: '/world' must not start with '/'"),
                ("base_frame", "robot\tbase", "parameter ~base_frame: 'robot\tbase' must not contain spaces"),
                ("tf_prefix", "robot 1", "parameter ~tf_prefix: 'robot 1' must not contain spaces")):
            code, out = run_node("__name:=bad_value_" + name, "_%s:=%s" % (name, value))
            self.assertNotEqual(code, 0, out[-2000:])
            self.assertIn(message, out)

    def test_bad_sensor_parameters_are_named(self):
        for value, message in (
                # the scene loader's checks and words, as for the file (the override path)
                ("{encoders: {rate: 0}}",
                 "parameter ~sensors/encoders/rate: sensors.encoders.rate: 0 is out of range (0, 1e+06] Hz"),
                ("{strain_gauges: {delay: 2.5}}",
                 "parameter ~sensors/strain_gauges/delay: sensors.strain_gauges.delay: 2.5 is not a whole number"),
                ("{accelerometer: {gyro_noise: -1.0}}", "parameter ~sensors/accelerometer/gyro_noise: "
                 "sensors.accelerometer.gyro_noise: -1 must be finite and at least 0"),
                ("{gyroscope: {rate: 100}}", "parameter ~sensors/gyroscope: sensors.gyroscope: unknown sensor "
                 "(allowed: encoders, strain_gauges, accelerometer)")):
            subprocess.run(["rosparam", "set", "/bad_sensors/sensors", value], check=True)
            code, out = run_node("__name:=bad_sensors")
            subprocess.run(["rosparam", "delete", "/bad_sensors/sensors"], check=True)
            self.assertNotEqual(code, 0, out[-2000:])
            self.assertIn(message, out)
        code, out = run_node("__name:=bad_sensors_text", "_sensors:={encoders: {}}")
        self.assertNotEqual(code, 0, out[-2000:])
        self.assertIn("parameter ~sensors: not a mapping", out)

    def test_use_sim_time_of_the_wrong_type_is_named(self):
        rospy.set_param("/use_sim_time", "yes")
        try:
            code, out = run_node("__name:=bad_sim_time")
        finally:
            rospy.delete_param("/use_sim_time")
        self.assertNotEqual(code, 0, out[-2000:])
        self.assertIn("parameter /use_sim_time: not a boolean", out)

    def test_accuracy_out_of_range_is_named(self):
        code, out = run_node("__name:=bad_accuracy", "_accuracy:=5.0")
        self.assertNotEqual(code, 0)
        self.assertIn("parameter ~accuracy: 5 is out of range 1e-09..1", out)

    def test_f_the_accuracy_knob_reports_its_choice_in_status(self):
        """~accuracy on a scene whose links leave their modes open: ~status carries the choice
        and its estimate (within the request), the log the reasoning, and the node runs."""
        from flex3rpr.msg import SimStatus
        seen = []
        sub = rospy.Subscriber("/knob/status", SimStatus, seen.append, queue_size=1000)
        proc = subprocess.Popen(["stdbuf", "-oL", "rosrun", "flex3rpr", "flex3rpr_node", "__name:=knob",
                                 "_scene:=" + PKG + "/test/scenes/open_modes.yaml", "_accuracy:=1e-4",
                                 "_realtime_factor:=1.0", "_publish_rate:=100.0"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            end = time.time() + 600
            while time.time() < end and not any(m.sim_time >= 0.05 for m in seen) and proc.poll() is None:
                time.sleep(0.1)
        finally:
            sub.unregister()
            proc.terminate()
            out, _ = proc.communicate(timeout=120)
        self.assertTrue(seen, out[-3000:])
        last = seen[-1]
        self.assertTrue(last.accuracy_choice.startswith("accuracy 0.0001 m: modes "), last.accuracy_choice)
        self.assertGreater(last.estimated_error, 0.0)
        self.assertLessEqual(last.estimated_error, 1e-4)
        self.assertIn("accuracy 0.0001 m on the end-effector path", out)
        self.assertIn("estimated error", out)
        # with a request the node measures the closed loop (~verify, on by default) on a thread
        # of its own while it runs paced
        self.assertEqual(last.error_basis, "measured")
        self.assertIn("~verify: the check configuration steps on the same commands", out)
        self.assertFalse(last.measured_error_m != last.measured_error_m, last.measurement_note)
        self.assertFalse(last.energy_guard)

    def test_g_the_energy_guard_warns(self):
        """Dormand-Prince 5(4) at rtol 3e-2 on fixed-free paper simulation 3 goes unstable and would
        run on to the end with garbage: past 0.1 of the largest T + V (between 0.1 and 0.15 s through
        the node's 10 ms periods; 0.056 at 0.1 s), ~status says energy_guard and
        /diagnostics warns (every wall second: at a real-time factor of 0.05, several times before the
        run could end), while the node keeps running."""
        from diagnostic_msgs.msg import DiagnosticArray
        from flex3rpr.msg import SimStatus
        seen, warnings = [], []
        sub = rospy.Subscriber("/guard/status", SimStatus, seen.append, queue_size=1000)
        diag = rospy.Subscriber("/diagnostics", DiagnosticArray,
                                lambda m: warnings.extend(s.message for s in m.status
                                                          if s.level == s.WARN and "guard" in s.name),
                                queue_size=100)
        proc = subprocess.Popen(["rosrun", "flex3rpr", "flex3rpr_node", "__name:=guard",
                                 "_scene:=" + PKG + "/config/scenes/paper_sim3_fixed_free.yaml",
                                 "_integrator:=erk", "_table:=ARKODE_DORMAND_PRINCE_7_4_5", "_rtol:=3e-2",
                                 "_realtime_factor:=0.05", "_publish_rate:=100.0"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            end = time.time() + 600
            while time.time() < end and proc.poll() is None and not (
                    any(m.sim_time >= 0.45 for m in seen) and any("energy balance" in w for w in warnings)):
                time.sleep(0.1)
        finally:
            sub.unregister()
            diag.unregister()
            proc.terminate()
            out, _ = proc.communicate(timeout=120)
        late = [m for m in seen if m.sim_time >= 0.45]
        self.assertTrue(late, out[-3000:])
        self.assertTrue(all(m.energy_guard for m in late))
        self.assertFalse(any(m.energy_guard for m in seen if m.sim_time <= 0.1))
        self.assertTrue(any("energy balance" in w for w in warnings), warnings[-5:])

    def test_mismatching_urdf_exits_with_the_joint_named(self):
        tree = ET.parse(PKG + "/urdf/flex3rpr.urdf")
        for joint in tree.getroot().iter("joint"):
            if joint.get("name") == "leg_1_revolute":
                origin = joint.find("origin")
                x, y, z = (float(v) for v in origin.get("xyz").split())
                origin.set("xyz", "%.15g %.15g %.15g" % (x + 1e-6, y, z))
        rospy.set_param("/mismatch/robot_description", ET.tostring(tree.getroot(), encoding="unicode"))
        code, out = run_node("__ns:=/mismatch")
        self.assertNotEqual(code, 0)
        self.assertIn("leg_1_revolute", out)
        self.assertIn("does not match", out)

    def test_runs_with_no_arguments(self):
        proc = subprocess.Popen(["stdbuf", "-oL", "rosrun", "flex3rpr", "flex3rpr_node"], stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)
        master = rosgraph.Master("/node_startup")
        try:
            end = time.time() + 300
            published = False
            while time.time() < end and not published:
                published = any(t == "/flex3rpr_node/status" for t, _ in master.getPublishedTopics(""))
                time.sleep(0.2)
            alive = proc.poll() is None
        finally:
            proc.terminate()
            out, _ = proc.communicate(timeout=120)
        self.assertTrue(published, "the node publishes ~status with no arguments; it said:\n" + out[-3000:])
        self.assertTrue(alive, "the node keeps running; it said:\n" + out[-3000:])
        self.assertIn("no robot_description parameter", out)

    def test_a_run_that_cannot_keep_its_factor_says_it_is_behind(self):
        """Paper sim. 3 asked for at 1000x real time: no machine keeps that, so ~status must say
        behind (achieved below 0.95 of the request), and the node must warn with the achieved
        factor. It never races to catch up: the schedule is re-anchored (~status.resyncs)."""
        from flex3rpr.msg import SimStatus
        seen = []
        sub = rospy.Subscriber("/behind/status", SimStatus, seen.append, queue_size=1000)
        proc = subprocess.Popen(["stdbuf", "-oL", "rosrun", "flex3rpr", "flex3rpr_node", "__name:=behind",
                                 "_scene:=" + PKG + "/config/scenes/paper_sim3_fixed_free.yaml",
                                 "_realtime_factor:=1000.0", "_publish_rate:=100.0"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            end = time.time() + 600
            while time.time() < end and not any(m.behind and m.resyncs > 0 for m in seen):
                time.sleep(0.1)
        finally:
            proc.terminate()
            out, _ = proc.communicate(timeout=120)
            sub.unregister()
        late = [m for m in seen if m.behind]
        self.assertTrue(late, "no ~status said behind; the node said:\n" + out[-3000:])
        self.assertEqual(late[-1].requested_realtime_factor, 1000.0)
        self.assertGreater(late[-1].realtime_factor, 0.0)
        self.assertTrue(all(m.realtime_factor < 950.0 for m in late), "behind means below 0.95 of the request")
        self.assertGreater(late[-1].resyncs, 0)
        self.assertIn("behind the wall clock", out)
        self.assertIn("of the requested 1000", out)

    def test_b_a_collapsed_leg_pauses_the_node_which_resets_and_runs_on(self):
        """A held command drives leg 1 into the collapse guard: the node pauses at the last good
        state with the error in ~status, keeps serving, and ~reset and ~resume run it on."""
        from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
        from flex3rpr.msg import EffortCommand, SimStatus
        from sensor_msgs.msg import JointState
        from std_srvs.srv import Empty, Trigger
        seen, joints, diagnostics = [], [], []
        subs = [rospy.Subscriber("/survivor/status", SimStatus, seen.append, queue_size=100000),
                rospy.Subscriber("/joint_states_survivor", JointState, joints.append, queue_size=100000),
                rospy.Subscriber("/diagnostics", DiagnosticArray, diagnostics.append, queue_size=100000)]
        pub = rospy.Publisher("/survivor/command", EffortCommand, queue_size=10)
        proc = subprocess.Popen(["stdbuf", "-oL", "rosrun", "flex3rpr", "flex3rpr_node", "__name:=survivor",
                                 "joint_states:=/joint_states_survivor",
                                 "_scene:=" + PKG + "/test/scenes/idle_rigid.yaml", "_realtime_factor:=0.0",
                                 "_publish_rate:=100.0"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            end = time.time() + 600
            while time.time() < end and not any(m.paused and "collapsed" in m.last_error for m in seen):
                pub.publish(EffortCommand(leg_force=[-200.0, 0.0, 0.0]))
                time.sleep(0.1)
            stopped = [m for m in seen if m.paused and "collapsed" in m.last_error]
            self.assertTrue(stopped, "no ~status reported the collapse")
            self.assertIsNone(proc.poll(), "the node died of its physics")
            t_stop = stopped[-1].sim_time
            pub.unregister()
            time.sleep(0.5)
            self.assertTrue(all(m.paused and m.sim_time == t_stop for m in seen[-3:]),
                            "paused at the last good state, still publishing ~status")
            # every topic goes on while it waits: joint_states at the stopped state, /diagnostics at ERROR
            held = len(joints)
            self.assertTrue(wait_until(lambda: len(joints) > held + 1), "joint_states stopped with the error")
            self.assertTrue(wait_until(lambda: any(
                s.name == "/survivor: simulation" and s.level == DiagnosticStatus.ERROR and "collapsed" in s.message
                for m in diagnostics for s in m.status)), "/diagnostics does not report the error")
            rospy.wait_for_service("/survivor/reset", timeout=120)
            self.assertTrue(rospy.ServiceProxy("/survivor/reset", Trigger)().success)
            rospy.ServiceProxy("/survivor/resume", Empty)()
            end = time.time() + 600
            while time.time() < end and not any(
                    not m.paused and m.sim_time > t_stop + 0.5 and not m.last_error for m in seen):
                time.sleep(0.1)
            self.assertTrue(any(not m.paused and m.sim_time > t_stop + 0.5 and not m.last_error for m in seen),
                            "after ~reset and ~resume the simulation runs on without an error")
            self.assertIsNone(proc.poll())
        finally:
            for sub in subs:
                sub.unregister()
            proc.terminate()
            out, _ = proc.communicate(timeout=120)
        self.assertIn("leg 1 collapsed", out)
        self.assertIn("paused at the last good state", out)


    def run_pushed(self, name, *params):
        """A node on idle_rigid.yaml (no end stops in the file) with leg 1 pushed outwards (3 N,
        held) until it pauses with an error or has run 3 s; returns its ~status messages,
        joint_states and output."""
        from flex3rpr.msg import EffortCommand, SimStatus
        from sensor_msgs.msg import JointState
        seen, joints = [], []
        subs = [rospy.Subscriber("/%s/status" % name, SimStatus, seen.append, queue_size=100000),
                rospy.Subscriber("/joint_states_%s" % name, JointState, joints.append, queue_size=100000)]
        pub = rospy.Publisher("/%s/command" % name, EffortCommand, queue_size=10)
        proc = subprocess.Popen(["stdbuf", "-oL", "rosrun", "flex3rpr", "flex3rpr_node", "__name:=" + name,
                                 "joint_states:=/joint_states_" + name, "_realtime_factor:=0.0",
                                 "_scene:=" + PKG + "/test/scenes/idle_rigid.yaml",
                                 "_publish_rate:=100.0", "_paused:=true", *params],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            # paused until the command is there: unpaced, 3 s take milliseconds
            from std_srvs.srv import Empty
            end = time.time() + 300
            while time.time() < end and pub.get_num_connections() == 0:
                time.sleep(0.05)
            pub.publish(EffortCommand(leg_force=[3.0, 0.0, 0.0]))
            time.sleep(0.5)
            rospy.wait_for_service("/%s/resume" % name, timeout=300)
            rospy.ServiceProxy("/%s/resume" % name, Empty)()
            end = time.time() + 600
            while time.time() < end and not any((m.paused and m.last_error) or m.sim_time > 3.0 for m in seen):
                time.sleep(0.1)
            self.assertIsNone(proc.poll(), "the node died of its physics")
        finally:
            for sub in subs:
                sub.unregister()
            pub.unregister()
            proc.terminate()
            out, _ = proc.communicate(timeout=120)
        self.assertTrue(seen, out[-3000:])
        return seen, joints, out

    def test_c_leaving_the_stroke_is_reported_once(self):
        seen, _, out = self.run_pushed("stroke")
        outside = [m for m in seen if m.outside_stroke[0]]
        self.assertTrue(outside, "rho_1 left 0..0.2 m; ~status.outside_stroke[0] says so")
        self.assertGreater(max(m.sim_time for m in outside) - min(m.sim_time for m in outside), 0.05,
                           "and stayed outside for a while")
        self.assertEqual(out.count("leg 1 left its stroke 0..0.2 m"), 1, out[-3000:])

    def test_d_end_stops_from_a_parameter_keep_the_stroke(self):
        seen, joints, out = self.run_pushed("stops", "_end_stops:=true")
        self.assertFalse(any(m.outside_stroke[0] for m in seen))
        self.assertNotIn("left its stroke", out)
        rho = [m.position[m.name.index("leg_1_prismatic")] for m in joints]
        self.assertTrue(rho)
        self.assertGreater(max(rho), 0.2 - 1e-3, "leg 1 reached its stop")
        self.assertLess(max(rho), 0.2 + 1e-6)

    def test_e_paused_at_the_start_until_a_step(self):
        from flex3rpr.msg import SimStatus
        from std_srvs.srv import Trigger
        seen = []
        sub = rospy.Subscriber("/waiting/status", SimStatus, seen.append, queue_size=1000)
        proc = subprocess.Popen(["rosrun", "flex3rpr", "flex3rpr_node", "__name:=waiting", "_paused:=true",
                                 "_publish_rate:=100.0"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            rospy.wait_for_service("/waiting/step", timeout=300)
            end = time.time() + 300
            while time.time() < end and len(seen) < 3:
                time.sleep(0.1)
            self.assertTrue(seen and all(m.paused and m.sim_time == 0.0 for m in seen))
            self.assertTrue(rospy.ServiceProxy("/waiting/step", Trigger)().success)
            end = time.time() + 300
            while time.time() < end and not any(m.sim_time > 0.0 for m in seen):
                time.sleep(0.1)
            self.assertAlmostEqual(max(m.sim_time for m in seen), 0.01, places=12)
            self.assertTrue(seen[-1].paused)
        finally:
            sub.unregister()
            proc.terminate()
            proc.communicate(timeout=120)


if __name__ == "__main__":
    rospy.init_node("node_startup", anonymous=True)
    rostest.rosrun("flex3rpr", "node_startup", NodeStartup)

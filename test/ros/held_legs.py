#!/usr/bin/env python3
"""rostest of flex3rpr_node's end stops holding several legs at once (held_legs.test), through
~step_with_command, one publish period a call (the node is paused): legs 1 and 2 pushed outwards
(100 N each) until both are locked at the stroke's maximum, then, with those pushes kept, leg 3
pushed out and pulled in three times.

After every period: every stroke within the stops to 1e-9 m; every locked leg within 1e-9 m of its
stop, its stop force pushing (a free leg has none); ~status never reports outside_stroke, the
energy guard or an error; and the Python module, given the same commands, has the same strokes,
locks and stop forces to the bit (flex3rpr.Sim, as python_equals_node.py).

test_a: leg 3 is driven by a speed-limited push of at most 60 N, so that it reaches its stop at
under 1 cm/s, and held at 60 N once locked there. Legs 1 and 2 stay locked at the maximum
throughout, their stop forces negative; leg 3 locks while pushed out and is released while pulled
in; with all three locked the platform is at rest and each stop's force balances its leg's push
(f_i = -F_i: with no load on the platform and a regular actuation map the legs carry nothing).

test_b: leg 3 pushed by +60 N and pulled by -60 N, 0.3 s each, three times. Leg 3 then reaches its
stops at over 1 m/s; with legs 1 and 2 held the mechanism has one degree of freedom, and stopping
it at once takes impulses that would pull legs 1 and 2 off their stops, which a stop cannot give:
the impact (one complementarity problem over every leg in contact, src/core/solve/contacts.c)
lifts them off, and their pushes bring them back. So legs 1 and 2 are not required to stay locked
there (the test prints how often they were not); every invariant above still holds, and all three
are locked once leg 3 has been held out for 0.3 s."""
import math
import sys
import threading
import unittest
import xml.etree.ElementTree as ET

import rospy
import rostest
from std_srvs.srv import Trigger

import flex3rpr
from flex3rpr.msg import EffortCommand, SimStatus
from flex3rpr.srv import StepWithCommand

NODE = "/flex3rpr_node"
TOL = 1e-9          # m: no stroke past a stop, no locked leg off its stop
FORCE_TOL = 1e-6    # N: a locked leg's stop force may not pull (the release root fires at 1e-8 N)
HOLD = 100.0        # N outwards on legs 1 and 2
PUSH = 60.0         # N: the largest push or pull on leg 3
LOCK_PERIODS = 1000  # the most periods legs 1 and 2 may take to lock


class Statuses:
    """~status by period (one per period the node integrates, and repeats while paused). A status
    at t = 0 starts a run: what came before it (a reset's predecessor) is dropped."""

    def __init__(self, rate):
        self.rate = rate
        self.cond = threading.Condition()
        self.by_period = {}
        rospy.Subscriber(NODE + "/status", SimStatus, self._status, queue_size=None)

    def _status(self, m):
        with self.cond:
            if m.sim_time == 0.0:
                self.by_period.clear()
            self.by_period[int(round(m.sim_time * self.rate))] = m
            self.cond.notify_all()

    def at(self, t, timeout=60.0):
        k = int(round(t * self.rate))
        with self.cond:
            if not self.cond.wait_for(lambda: k in self.by_period and
                                      self.by_period[k].sim_time == t, timeout):
                raise AssertionError("no ~status for t = %.6g s within %g wall s" % (t, timeout))
            return self.by_period[k]


class HeldLegs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("held_legs", anonymous=True)
        for name in ("reset", "step_with_command"):
            rospy.wait_for_service(NODE + "/" + name, timeout=120)
        cls.reset = rospy.ServiceProxy(NODE + "/reset", Trigger)
        cls.step_srv = rospy.ServiceProxy(NODE + "/step_with_command", StepWithCommand,
                                          persistent=True)
        cls.rate = rospy.get_param(NODE + "/publish_rate", 1000.0)
        cls.statuses = Statuses(cls.rate)
        # the stroke, as the URDF's prismatic limits (the node checked them against the scene)
        urdf = ET.fromstring(rospy.get_param("/robot_description"))
        limits = {j.get("name"): (float(j.find("limit").get("lower")),
                                  float(j.find("limit").get("upper")))
                  for j in urdf.iter("joint") if j.get("name").endswith("_prismatic")}
        cls.lo, cls.hi = limits["leg_1_prismatic"]
        assert all(v == (cls.lo, cls.hi) for v in limits.values()), limits
        assert rospy.get_param(NODE + "/end_stops"), "held_legs.test runs with end stops"
        cls.scene = rospy.get_param(NODE + "/scene")

    # --- one period ---------------------------------------------------------------------------
    def start(self):
        """The node back at t = 0 (paused), and a Python shadow of it."""
        res = self.reset()
        self.assertTrue(res.success, res.message)
        status = self.statuses.at(0.0)
        self.assertEqual(list(status.stop_locked), [0, 0, 0])
        self.sim = flex3rpr.Sim(self.scene, overrides={"effects.end_stops": {}},
                                period=1.0 / self.rate)
        self.worst_penetration = -math.inf  # m past a stop (negative: never at one)
        self.worst_drift = 0.0              # m off its stop while locked
        self.periods = 0
        self.res = None

    def step(self, forces, where):
        """One period with leg forces `forces`; every invariant checked. Returns (rho, rho_dot,
        status)."""
        res = self.step_srv(command=EffortCommand(leg_force=list(forces)), periods=1)
        self.assertTrue(res.success, "%s: %s" % (where, res.message))
        st = self.statuses.at(res.sim_time)
        self.periods += 1
        self.res = res
        js = res.joint_state
        names = list(js.name)
        idx = [names.index("leg_%d_prismatic" % (i + 1)) for i in range(3)]
        rho = [js.position[k] for k in idx]
        rate = [js.velocity[k] for k in idx]
        where = "%s, t = %.3f s: rho %s, stop_locked %s, stop_force %s" % (
            where, res.sim_time, rho, list(st.stop_locked), list(st.stop_force))
        for i in range(3):
            past = max(rho[i] - self.hi, self.lo - rho[i])
            self.worst_penetration = max(self.worst_penetration, past)
            self.assertLessEqual(past, TOL, "leg %d past its stop; %s" % (i + 1, where))
            side = st.stop_locked[i]
            self.assertIn(side, (-1, 0, 1), where)
            if side:
                drift = abs(rho[i] - (self.hi if side > 0 else self.lo))
                self.worst_drift = max(self.worst_drift, drift)
                self.assertLessEqual(drift, TOL, "leg %d off its stop; %s" % (i + 1, where))
                self.assertLessEqual(side * st.stop_force[i], FORCE_TOL,
                                     "leg %d's stop pulls; %s" % (i + 1, where))
            else:
                self.assertEqual(st.stop_force[i], 0.0, "free leg %d; %s" % (i + 1, where))
        self.assertEqual(list(st.outside_stroke), [False] * 3, where)
        self.assertFalse(st.energy_guard, where)
        self.assertEqual(st.last_error, "", where)
        # the Python module, the same command: the same period to the bit
        s = self.sim.step({"leg_force": list(forces)})
        extras = self.sim.extras
        self.assertEqual(res.sim_time, s.t, where)
        self.assertEqual(rho, s.q[:3].tolist(), "Python's strokes differ; " + where)
        self.assertEqual(list(st.stop_locked), extras["stop_locked"].tolist(),
                         "Python's locks differ; " + where)
        self.assertEqual(list(st.stop_force), extras["stop_force"].tolist(),
                         "Python's stop forces differ; " + where)
        return rho, rate, st

    def lock_legs_1_and_2(self):
        """Legs 1 and 2 pushed out until both are locked at the maximum; returns the last step."""
        for k in range(LOCK_PERIODS):
            rho, rate, st = self.step((HOLD, HOLD, 0.0), "pushing legs 1 and 2 out")
            if list(st.stop_locked[:2]) == [1, 1]:
                return rho, rate, st
        self.fail("legs 1 and 2 not both locked after %d periods of %g N: stop_locked %s"
                  % (LOCK_PERIODS, HOLD, list(st.stop_locked)))

    def assert_legs_1_and_2_held(self, rho, st, where):
        self.assertEqual(list(st.stop_locked[:2]), [1, 1], "legs 1 and 2 not held; " + where)
        for i in range(2):
            self.assertLessEqual(abs(rho[i] - self.hi), TOL, where)
            self.assertLess(st.stop_force[i], 0.0, where)

    def report(self, name, extra=""):
        print("%s: %d periods, worst penetration %.3g m, worst locked drift %.3g m%s"
              % (name, self.periods, self.worst_penetration, self.worst_drift, extra))
        sys.stdout.flush()

    # --- the tests ----------------------------------------------------------------------------
    def test_a_legs_1_and_2_stay_held_while_leg_3_moves_in_and_out(self):
        self.start()
        rho, rate, st = self.lock_legs_1_and_2()

        def drive(target, rho3, rate3):
            """Leg 3's force: a speed-limited push towards target (decelerating at 4 m/s^2, at most
            0.5 m/s), at most PUSH."""
            d = target - rho3
            v = math.copysign(min(0.5, math.sqrt(2.0 * 4.0 * abs(d))), d)
            return max(-PUSH, min(PUSH, 200.0 * (v - rate3)))

        middle = 0.5 * (self.lo + self.hi)
        impacts = st.impacts
        for cycle in range(3):
            # out for 0.4 s: leg 3 comes to its stop at under 1 cm/s, then is held there at PUSH
            where = "cycle %d, leg 3 pushed out" % (cycle + 1)
            locked_at = None
            for k in range(400):
                f3 = PUSH if st.stop_locked[2] == 1 else drive(self.hi + 2e-5, rho[2], rate[2])
                rho, rate, st = self.step((HOLD, HOLD, f3), where)
                self.assert_legs_1_and_2_held(rho, st, where)
                if locked_at is None and st.stop_locked[2] == 1:
                    locked_at = k
                if locked_at is not None:
                    self.assertEqual(st.stop_locked[2], 1, "leg 3 let go while pushed; " + where)
            self.assertIsNotNone(locked_at, "leg 3 never locked; " + where)
            # all three held, the platform at rest: the legs carry nothing, the stops take the push
            self.assertLess(st.actuation_condition, 1e3, where)
            self.assertLess(max(abs(v) for v in self.res.platform_twist), 1e-3, where)
            for i, f in enumerate((HOLD, HOLD, PUSH)):
                self.assertAlmostEqual(st.stop_force[i], -f, delta=1.0,
                                       msg="leg %d's stop force; %s" % (i + 1, where))
            print("%s: leg 3 locked after %d ms; stop forces %s N" % (
                where, locked_at + 1, ["%.3f" % f for f in st.stop_force]))
            # in for 0.3 s, towards mid-stroke: leg 3 released at once
            where = "cycle %d, leg 3 pulled in" % (cycle + 1)
            for k in range(300):
                rho, rate, st = self.step((HOLD, HOLD, drive(middle, rho[2], rate[2])), where)
                self.assert_legs_1_and_2_held(rho, st, where)
                if k >= 5:
                    self.assertEqual(st.stop_locked[2], 0, "leg 3 held while pulled; " + where)
            self.assertLess(rho[2], self.hi - 1e-3, where)
        # Not asserted, reported: the count includes the re-lockings of held legs at the restarts
        # where leg 3's command changes (every period here), which leg 3's six arrivals alone
        # would not explain.
        self.report("test_a (speed-limited leg 3)",
                    ", %d impacts during leg 3's moves" % (st.impacts - impacts))

    def test_b_leg_3_slammed_in_and_out_keeps_every_leg_within_its_stops(self):
        self.start()
        rho, rate, st = self.lock_legs_1_and_2()
        knocked_off = 0  # periods with leg 1 or 2 not locked
        impacts = st.impacts
        for cycle in range(3):
            for f3, sign in ((PUSH, 1), (-PUSH, -1)):
                where = "cycle %d, leg 3 at %+g N" % (cycle + 1, f3)
                for k in range(300):
                    rho, rate, st = self.step((HOLD, HOLD, f3), where)
                    knocked_off += list(st.stop_locked[:2]) != [1, 1]
                    if sign < 0 and k >= 5:
                        self.assertNotEqual(st.stop_locked[2], 1,
                                            "leg 3 held out while pulled; " + where)
                if sign > 0:  # held out for 0.3 s: all three locked at the maximum
                    self.assertEqual(list(st.stop_locked), [1, 1, 1], where)
                    for i in range(3):
                        self.assertLess(st.stop_force[i], 0.0, where)
                else:
                    self.assertLess(rho[2], self.hi - 1e-3, where)
        self.report("test_b (leg 3 at +-60 N)",
                    ", legs 1 or 2 lifted off their stops in %d of %d periods of leg 3's moves, "
                    "%d impacts" % (knocked_off, 1800, st.impacts - impacts))


if __name__ == "__main__":
    rostest.rosrun("flex3rpr", "held_legs", HeldLegs, sys.argv)

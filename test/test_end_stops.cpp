// End stops held as contact: a leg that comes to rest against its stop locks there, its stop's
// force is the contact's Lagrange multiplier (queries.h f3r_stop_forces), and it releases where
// that force would have to pull. The static cases check the force against the platform's
// equilibrium computed here from the geometry alone.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "test_support.h"

namespace {

// rest.yaml (1 % modal damping, viscous joint friction) with end stops at [lo, hi]
ModelPtr StopModel(double lo, double hi, const std::string& solver = "") {
  const std::string path = WriteTemp(
      "end_stops.yaml",
      "links: {model: fixed_free, modes: 2, damping_ratio: 0.01}\n"
      "effects:\n  joint_friction: {prismatic: [5.0, 5.0, 5.0], revolute: [0.01, 0.01, 0.01]}\n"
      "  end_stops: {min: " +
          std::to_string(lo) + ", max: " + std::to_string(hi) + ", restitution: 0.5}\n" + solver +
          "run: {duration: 1.0}\n");
  return LoadModel(path);
}

struct StopRun {
  ModelPtr model;
  SimPtr sim;
  std::vector<double> held;
  explicit StopRun(ModelPtr m) : model(std::move(m)), held(model->nq, 0.0) {
    f3r_sim* raw = nullptr;
    f3r_error err{};
    EXPECT_EQ(f3r_sim_create(model.get(), nullptr, &raw, &err), F3R_OK) << err.message;
    sim.reset(raw);
  }
  // holds `held` from now to t, checking every 10 ms that no stroke passes a stop
  const f3r_outputs* HoldTo(double t, double* deepest = nullptr) {
    f3r_error err{};
    EXPECT_EQ(f3r_sim_set_forces(sim.get(), held.data(), &err), F3R_OK) << err.message;
    const f3r_geometry g = f3r_model_geometry(model.get());
    for (double next = f3r_sim_time(sim.get()) + 0.01; next < t + 5e-3; next += 0.01) {
      EXPECT_EQ(f3r_sim_advance(sim.get(), std::min(next, t), &err), F3R_OK) << err.message;
      const f3r_outputs* o = f3r_sim_outputs(sim.get());
      for (int i = 0; i < 3 && deepest; ++i)
        *deepest = std::max({*deepest, o->q[i] - g.stroke_max, g.stroke_min - o->q[i]});
    }
    return f3r_sim_outputs(sim.get());
  }
};

// The platform's static equilibrium: leg i pushes it along u_i (from A_i to C_i) with T_i, so
// sum T_i u_i + F = 0 and sum r_i x T_i u_i + M = 0 (the beams straight, at rest).
Eigen::Vector3d EquilibriumLegForces(const f3r_model* m, const double* q, const double wrench[3]) {
  const f3r_geometry g = f3r_model_geometry(m);
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i) {
    const double a = q[F3R_Q_PHI] + g.platform_angle[i];
    const double rx = g.platform_radius * std::cos(a), ry = g.platform_radius * std::sin(a);
    const double ux0 = q[F3R_Q_X] + rx - g.base_joint[i][0],
                 uy0 = q[F3R_Q_Y] + ry - g.base_joint[i][1];
    const double len = std::hypot(ux0, uy0), ux = ux0 / len, uy = uy0 / len;
    A.col(i) << ux, uy, rx * uy - ry * ux;
  }
  return A.lu().solve(-Eigen::Vector3d(wrench[0], wrench[1], wrench[2]));
}

TEST(EndStops, AForceHeldAgainstAStopFor10sIsHeldByTheStop) {
  StopRun run(StopModel(0.0, 0.2));
  run.held[0] = 30.0;  // leg 1 pushed outwards, into stroke_max
  double deepest = -1.0;
  const f3r_outputs* o = run.HoldTo(10.0, &deepest);
  std::printf(
      "measured: 30 N held 10 s: rho_1 - max %.2e m, stop force %.9g N, %ld impacts, "
      "energy balance %.1e J, deepest %.1e m\n",
      o->q[0] - 0.2, o->stop_force[0], o->impacts, o->energy_balance_error, deepest);
  EXPECT_EQ(o->stop_locked[0], 1);
  EXPECT_NEAR(o->q[0], 0.2, 1e-9);
  EXPECT_LT(deepest, 1e-9);
  // legs 2 and 3 free and unloaded: the stop alone balances the push
  EXPECT_NEAR(o->stop_force[0], -30.0, 1e-6);
  EXPECT_EQ(o->stop_force[1], 0.0);
  EXPECT_LT(o->energy_balance_error, 1e-5);  // of the 2.4 J the push did
  EXPECT_EQ(o->actuator[0], 30.0);           // the reaction stays out of the actuator's effort
}

TEST(EndStops, PushReleaseAndPushAgain) {
  StopRun run(StopModel(0.0, 0.2));
  run.held[0] = 30.0;
  const f3r_outputs* o = run.HoldTo(2.0);
  ASSERT_EQ(o->stop_locked[0], 1);
  const long first = o->impacts;
  run.held[0] = -5.0;  // pulls the leg off its stop: the stop would have to pull, so it lets go
  o = run.HoldTo(2.3);
  EXPECT_EQ(o->stop_locked[0], 0);
  EXPECT_LT(o->q[0], 0.2 - 1e-3);
  EXPECT_EQ(o->stop_force[0], 0.0);
  run.held[0] = 30.0;
  double deepest = -1.0;
  o = run.HoldTo(5.0, &deepest);
  std::printf("measured: push, release, push: %ld impacts; stop force %.9g N\n", o->impacts,
              o->stop_force[0]);
  EXPECT_EQ(o->stop_locked[0], 1);
  EXPECT_GT(o->impacts, first);
  EXPECT_NEAR(o->stop_force[0], -30.0, 1e-6);
  EXPECT_LT(deepest, 1e-9);
}

// A platform wrench drives it until all three legs rest at stops: their forces then balance the
// wrench, as the geometry's statics say.
void ExpectWrenchHeld(const char* name, const std::string& solver) {
  StopRun run(StopModel(0.11, 0.13, solver));
  const double wrench[3] = {20.0, 10.0, 1.0};
  for (int c = 0; c < 3; ++c) run.held[F3R_Q_X + c] = wrench[c];
  double deepest = -1.0;
  const f3r_outputs* o = run.HoldTo(10.0, &deepest);
  const Eigen::Vector3d T = EquilibriumLegForces(run.model.get(), o->q, wrench);
  std::printf(
      "measured (%s): stop forces %.9g %.9g %.9g N, statics %.9g %.9g %.9g N (apart "
      "%.1e N); %ld impacts, deepest %.1e m\n",
      name, o->stop_force[0], o->stop_force[1], o->stop_force[2], T[0], T[1], T[2],
      (Eigen::Vector3d(o->stop_force[0], o->stop_force[1], o->stop_force[2]) - T)
          .cwiseAbs()
          .maxCoeff(),
      o->impacts, deepest);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NE(o->stop_locked[i], 0) << "leg " << i + 1;
    EXPECT_NEAR(o->stop_force[i], T[i], 1e-6 * T.norm()) << "leg " << i + 1;
  }
  EXPECT_LT(deepest, 1e-9);
  EXPECT_LT(o->energy_balance_error, 1e-5);
}

TEST(EndStops, APlatformWrenchPushesAllThreeLegsIntoStopsThatBalanceIt) {
  ExpectWrenchHeld("minimal, IDA", "");
}

TEST(EndStops, TheRedundantFormulationHoldsTheSameWrench) {
  ExpectWrenchHeld("dae, IDA", "solver: {formulation: dae}\n");
}

TEST(EndStops, AnExplicitIntegratorHoldsTheSameWrench) {
  ExpectWrenchHeld("minimal, ERK", "solver: {integrator: erk}\n");
}

// --- several legs in contact at once ------------------------------------------------------------

// Every leg locked in run r: its stroke on its stop to 1e-9 m.
void ExpectLockedOnStops(const StopRun& run, const f3r_outputs* o, const char* when) {
  const f3r_geometry g = f3r_model_geometry(run.model.get());
  for (int i = 0; i < 3; ++i) {
    if (!o->stop_locked[i]) continue;
    EXPECT_NEAR(o->q[i], o->stop_locked[i] < 0 ? g.stroke_min : g.stroke_max, 1e-9)
        << when << ": leg " << i + 1;
  }
}

// Legs 1 and 2 pushed out, leg 3 free and unloaded: at rest leg 3 carries nothing, so the platform
// is balanced only if legs 1 and 2 carry nothing either: each stop takes its leg's push.
TEST(EndStops, TwoLegsHeldAtOnceEachStopTakesItsPush) {
  StopRun run(StopModel(0.0, 0.2));
  run.held[0] = 40.0;
  run.held[1] = 70.0;
  double deepest = -1.0;
  const f3r_outputs* o = run.HoldTo(6.0, &deepest);
  std::printf("measured: two legs held: stop forces %.9g %.9g %.9g N, energy balance %.1e J\n",
              o->stop_force[0], o->stop_force[1], o->stop_force[2], o->energy_balance_error);
  EXPECT_EQ(o->stop_locked[0], 1);
  EXPECT_EQ(o->stop_locked[1], 1);
  EXPECT_EQ(o->stop_locked[2], 0);
  EXPECT_NEAR(o->stop_force[0], -40.0, 1e-6);
  EXPECT_NEAR(o->stop_force[1], -70.0, 1e-6);
  ExpectLockedOnStops(run, o, "two held");
  EXPECT_LT(deepest, 1e-9);
  EXPECT_LT(o->energy_balance_error, 1e-5);
}

// Leg 1 held at its stop while leg 2 is driven into its own again and again (restitution 0.5):
// no impact of leg 2 lifts leg 1 off, and leg 1's stop ends taking its push.
TEST(EndStops, AHeldLegStaysWhileItsNeighbourImpacts) {
  StopRun run(StopModel(0.0, 0.2));
  run.held[0] = 50.0;
  const f3r_outputs* o = run.HoldTo(2.0);
  ASSERT_EQ(o->stop_locked[0], 1);
  double deepest = -1.0;
  const long before = o->impacts;
  for (int k = 0; k < 4; ++k) {  // leg 2 out into its stop, then back in
    run.held[1] = 80.0;
    o = run.HoldTo(2.0 + 0.5 * k + 0.25, &deepest);
    EXPECT_EQ(o->stop_locked[0], 1) << "push " << k;
    ExpectLockedOnStops(run, o, "neighbour pushed");
    run.held[1] = -30.0;
    o = run.HoldTo(2.0 + 0.5 * k + 0.5, &deepest);
    EXPECT_EQ(o->stop_locked[0], 1) << "pull " << k;
    ExpectLockedOnStops(run, o, "neighbour pulled");
  }
  EXPECT_GT(o->impacts, before + 4);  // leg 2 hit its stop each time
  run.held[1] = 0.0;
  o = run.HoldTo(8.0, &deepest);
  std::printf(
      "measured: held leg beside an impacting one: %ld impacts, stop force %.9g N, "
      "energy balance %.1e J, deepest %.1e m\n",
      o->impacts, o->stop_force[0], o->energy_balance_error, deepest);
  EXPECT_NEAR(o->stop_force[0], -50.0, 1e-6);
  EXPECT_LT(deepest, 1e-9);
  EXPECT_LT(o->energy_balance_error, 1e-4);
}

// Leg 1 pulled off its stop at the instant leg 2 is pushed into its own: one releases, the other
// locks, and each stop then takes what statics says.
TEST(EndStops, AReleaseWhileAnotherLegLocks) {
  StopRun run(StopModel(0.0, 0.2));
  run.held[0] = 60.0;
  const f3r_outputs* o = run.HoldTo(2.0);
  ASSERT_EQ(o->stop_locked[0], 1);
  run.held[0] = -10.0;
  run.held[1] = 60.0;
  double deepest = -1.0;
  o = run.HoldTo(2.05, &deepest);
  EXPECT_EQ(o->stop_locked[0], 0);
  o = run.HoldTo(6.0, &deepest);
  std::printf("measured: release and lock: locks %d %d %d, stop forces %.9g %.9g %.9g N\n",
              o->stop_locked[0], o->stop_locked[1], o->stop_locked[2], o->stop_force[0],
              o->stop_force[1], o->stop_force[2]);
  EXPECT_EQ(o->stop_locked[1], 1);
  EXPECT_NEAR(o->stop_force[1], -60.0, 1e-6);
  // leg 1, pulled inwards, rests on its lower stop (nothing else holds it)
  EXPECT_EQ(o->stop_locked[0], -1);
  EXPECT_NEAR(o->stop_force[0], 10.0, 1e-6);
  ExpectLockedOnStops(run, o, "after the exchange");
  EXPECT_LT(deepest, 1e-9);
  EXPECT_LT(o->energy_balance_error, 1e-4);
}

// A platform wrench that turns from plateau to plateau moves the contacts from stop to stop; at
// rest on each plateau the stop forces balance the wrench, and a leg left free is one that statics
// leaves unloaded (the platform turned until the wrench's line meets the other two legs').
TEST(EndStops, AWrenchMovesTheContactsFromLegToLeg) {
  StopRun run(StopModel(0.11, 0.13));
  const double wrenches[3][3] = {{20.0, 10.0, 1.0}, {-25.0, 5.0, -0.5}, {5.0, -30.0, 0.8}};
  double deepest = -1.0;
  int sides_changed = 0, previous[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 3; ++c) run.held[F3R_Q_X + c] = wrenches[k][c];
    const f3r_outputs* o = run.HoldTo(4.0 * (k + 1), &deepest);
    const Eigen::Vector3d T = EquilibriumLegForces(run.model.get(), o->q, wrenches[k]);
    std::printf(
        "measured: wrench %d: locks %d %d %d, stop forces %.9g %.9g %.9g N, statics "
        "%.9g %.9g %.9g N\n",
        k + 1, o->stop_locked[0], o->stop_locked[1], o->stop_locked[2], o->stop_force[0],
        o->stop_force[1], o->stop_force[2], T[0], T[1], T[2]);
    for (int i = 0; i < 3; ++i) {
      if (!o->stop_locked[i]) {
        EXPECT_NEAR(T[i], 0.0, 1e-6 * T.norm()) << "leg " << i + 1;
      }
      EXPECT_NEAR(o->stop_force[i], T[i], 1e-6 * T.norm()) << "wrench " << k + 1;
      sides_changed += k > 0 && o->stop_locked[i] != previous[i];
      previous[i] = o->stop_locked[i];
    }
    ExpectLockedOnStops(run, o, "wrench");
    EXPECT_LT(o->energy_balance_error, 1e-4);
  }
  EXPECT_GT(sides_changed, 0);  // the contacts moved
  EXPECT_LT(deepest, 1e-9);
}

}  // namespace

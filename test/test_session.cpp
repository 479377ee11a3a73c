// The session (flex3rpr/session.h), the one place every shell's checks live: commands refused
// for their length, a value that is not finite or beyond the scene's limits, bad periods and
// states out of the scene's ranges, each naming what was wrong and changing nothing; a step that
// fails undone bit for bit, sensors included; and a scene's limits fields.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "flex3rpr/session.h"
#include "test_support.h"

namespace {

struct SessionDeleter {
  void operator()(f3r_session* s) const { f3r_session_close(s); }
};
using SessionPtr = std::unique_ptr<f3r_session, SessionDeleter>;

SessionPtr Open(const std::string& path, std::vector<const char*> sets = {}) {
  f3r_session_options options{};
  options.overrides = sets.data();
  options.override_count = static_cast<int>(sets.size());
  options.commanded = 1;
  f3r_session* s = nullptr;
  f3r_error err{};
  if (f3r_session_open(path.c_str(), &options, &s, &err) != F3R_OK)
    throw std::runtime_error(err.message);
  return SessionPtr(s);
}

// Everything a caller can read of a session, as bits: time, periods, outputs and sensors.
std::vector<double> Snapshot(f3r_session* s) {
  const f3r_outputs* o = f3r_sim_outputs(f3r_session_sim(s));
  const int nq = f3r_model_nq(f3r_session_model(s));
  std::vector<double> v = {o->t, static_cast<double>(f3r_session_periods(s)),
                           static_cast<double>(o->impacts), o->energy_balance_error};
  v.insert(v.end(), o->q, o->q + nq);
  v.insert(v.end(), o->v, o->v + nq);
  v.insert(v.end(), o->actuator, o->actuator + 6);
  v.insert(v.end(), o->passive, o->passive + 6);
  v.insert(v.end(), o->lambda, o->lambda + 6);
  v.insert(v.end(), o->stop_force, o->stop_force + 3);
  for (int i = 0; i < 3; ++i) v.push_back(o->stop_locked[i]);
  if (const f3r_sensors* sensors = f3r_session_sensors(s))
    for (int k = 0; k < f3r_sensor_kind_count(); ++k) {
      const f3r_sensor_reading* r = f3r_sensors_reading(sensors, k);
      v.insert(v.end(), r->value, r->value + r->channels);
      v.push_back(static_cast<double>(r->sample));
    }
  return v;
}

bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

std::vector<double> Forces(f3r_session* s, std::vector<std::pair<int, double>> set = {}) {
  std::vector<double> f(static_cast<size_t>(f3r_model_nq(f3r_session_model(s))), 0.0);
  for (const auto& [n, value] : set) f[static_cast<size_t>(n)] = value;
  return f;
}

const char* const kSensorScene = F3R_SOURCE_DIR "/test/scenes/sensors_fixed_free.yaml";

TEST(Session, OpensWithTheSceneLimitsAndNamesABadScene) {
  auto s = Open(kSensorScene);
  EXPECT_EQ(f3r_session_scene(s.get())->limit_force, 1000.0);
  EXPECT_EQ(f3r_session_scene(s.get())->limit_torque, 100.0);
  EXPECT_EQ(f3r_session_scene(s.get())->limit_modal_force, 1000.0);
  EXPECT_NE(f3r_session_sensors(s.get()), nullptr);
  auto custom = Open(kSensorScene, {"limits.force=50", "limits.torque=2"});
  EXPECT_EQ(f3r_session_scene(custom.get())->limit_force, 50.0);

  f3r_session* bad = nullptr;
  f3r_error err{};
  const char* sets[] = {"limits.force=-1"};
  f3r_session_options options{0.0, sets, 1, 1, 0, 0};
  EXPECT_EQ(f3r_session_open(kSensorScene, &options, &bad, &err), F3R_ERR_SCENE);
  EXPECT_EQ(bad, nullptr);
  EXPECT_NE(std::string(err.message).find("limits.force"), std::string::npos) << err.message;
  EXPECT_NE(std::string(err.message).find("1e-06..1e+09"), std::string::npos) << err.message;
  const char* excitation[] = {"accuracy.excitation=-5"};
  options.overrides = excitation;
  EXPECT_EQ(f3r_session_open(kSensorScene, &options, &bad, &err), F3R_ERR_SCENE);
  EXPECT_NE(std::string(err.message).find("accuracy.excitation: -5 is out of range 1e-06..1e+09"),
            std::string::npos)
      << err.message;
}

// Every refusal names the value and changes nothing, bit for bit.
TEST(Session, RefusedCommandsAndStepsNameTheFieldAndChangeNothing) {
  auto s = Open(kSensorScene, {"limits.force=200"});
  f3r_error err{};
  auto good = Forces(s.get(), {{F3R_Q_RHO, 5.0}});
  ASSERT_EQ(f3r_session_step(s.get(), good.data(), static_cast<int>(good.size()), 3, 1e-3, &err),
            F3R_OK)
      << err.message;
  const auto before = Snapshot(s.get());
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  const int nq = f3r_model_nq(f3r_session_model(s.get()));
  struct Case {
    std::vector<double> forces;
    int count;
    double periods, period;
    const char* names;
  };
  const std::vector<Case> cases = {
      {Forces(s.get()), 6, 1, 1e-3, "6 values, expected"},
      {Forces(s.get()), nq + 1, 1, 1e-3, "values, expected"},
      {Forces(s.get(), {{F3R_Q_RHO + 1, nan}}), nq, 1, 1e-3, "leg_force_2 is nan, not finite"},
      {Forces(s.get(), {{F3R_Q_THETA, -inf}}), nq, 1, 1e-3, "cylinder_torque_1 is -inf"},
      {Forces(s.get(), {{F3R_Q_RHO + 2, 200.5}}), nq, 1, 1e-3,
       "leg_force_3 is 200.5, out of range -200..200 (the scene's limits.force)"},
      {Forces(s.get(), {{F3R_Q_Y, -5000}}), nq, 1, 1e-3, "platform_force_y is -5000"},
      {Forces(s.get(), {{F3R_Q_PHI, 101}}), nq, 1, 1e-3,
       "platform_torque is 101, out of range -100..100 (the scene's limits.torque)"},
      {Forces(s.get(), {{F3R_Q_MODAL + 3, 1e12}}), nq, 1, 1e-3,
       "modal_force[3] is 1e+12, out of range -1000..1000 (the scene's limits.modal_force)"},
      {Forces(s.get()), nq, 2.9, 1e-3, "periods is 2.9"},
      {Forces(s.get()), nq, 0, 1e-3, "periods is 0"},
      {Forces(s.get()), nq, -3, 1e-3, "periods is -3"},
      {Forces(s.get()), nq, nan, 1e-3, "periods is nan"},
      {Forces(s.get()), nq, 1, 0.0, "period is 0 s"},
      {Forces(s.get()), nq, 1, -1e-3, "period is -0.001 s"},
      {Forces(s.get()), nq, 1, nan, "period is nan s"},
      {Forces(s.get()), nq, 1, 1e4, "period is 10000 s"},
  };
  for (const Case& c : cases) {
    err = {};
    EXPECT_EQ(f3r_session_step(s.get(), c.forces.data(), c.count, c.periods, c.period, &err),
              F3R_ERR_ARGUMENT)
        << c.names;
    EXPECT_NE(std::string(err.message).find(c.names), std::string::npos) << err.message;
    EXPECT_NE(std::string(err.message).find("nothing changed"), std::string::npos) << err.message;
    EXPECT_TRUE(SameBits(Snapshot(s.get()), before)) << c.names;
  }
  EXPECT_EQ(f3r_session_step(s.get(), nullptr, nq, 1, 1e-3, &err), F3R_ERR_ARGUMENT);
  // at the limit is within it
  auto edge = Forces(s.get(), {{F3R_Q_RHO, 200.0}, {F3R_Q_THETA, -100.0}});
  EXPECT_EQ(f3r_session_step(s.get(), edge.data(), nq, 1, 1e-3, &err), F3R_OK) << err.message;
}

TEST(Session, StatesOutOfTheSceneRangesAreRefusedAndChangeNothing) {
  auto s = Open(kSensorScene);
  f3r_error err{};
  const int n_modal = f3r_model_nq(f3r_session_model(s.get())) - F3R_Q_MODAL;
  ASSERT_EQ(n_modal, 6);
  const auto before = Snapshot(s.get());
  const double zero[3] = {0, 0, 0};
  std::vector<double> modal(6, 0.0), big(6, 0.0), fast(6, 0.0);
  big[2] = 1.0;
  fast[5] = -150.0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    std::vector<double> pose, twist;
    const double* modal;
    const double* rate;
    int count;
    const char* names;
  };
  const std::vector<Case> cases = {
      {{2.0, 0, 0}, {0, 0, 0}, nullptr, nullptr, 0, "pose[0] is 2: out of range -1..1"},
      {{0, -1.5, 0}, {0, 0, 0}, nullptr, nullptr, 0, "pose[1] is -1.5"},
      {{0, 0, 1e6},
       {0, 0, 0},
       nullptr,
       nullptr,
       0,
       "pose[2] is 1e+06: out of range -1000..1000 rad"},
      {{nan, 0, 0}, {0, 0, 0}, nullptr, nullptr, 0, "pose[0] is nan"},
      {{0, 0, 0}, {0, 2e3, 0}, nullptr, nullptr, 0, "twist[1] is 2000"},
      {{0, 0, 0}, {0, 0, nan}, nullptr, nullptr, 0, "twist[2] is nan"},
      {{0, 0, 0}, {0, 0, 0}, big.data(), nullptr, 6, "modal[2] is 1: out of range -0.1..0.1"},
      {{0, 0, 0}, {0, 0, 0}, modal.data(), fast.data(), 6, "modal_rate[5] is -150"},
      {{0, 0, 0}, {0, 0, 0}, modal.data(), nullptr, 5, "modal: 5 values, the model has 6"},
  };
  for (const Case& c : cases) {
    err = {};
    EXPECT_NE(f3r_session_set_state(s.get(), c.pose.data(), c.twist.data(), c.modal, c.rate,
                                    c.count, &err),
              F3R_OK)
        << c.names;
    EXPECT_NE(std::string(err.message).find(c.names), std::string::npos) << err.message;
    EXPECT_TRUE(SameBits(Snapshot(s.get()), before)) << c.names;
  }
  EXPECT_EQ(f3r_session_set_state(s.get(), nullptr, zero, nullptr, nullptr, 0, &err),
            F3R_ERR_ARGUMENT);
  // within the ranges it is taken
  const double pose[3] = {0.01, -0.01, 0.02};
  modal[0] = 1e-4;
  EXPECT_EQ(f3r_session_set_state(s.get(), pose, zero, modal.data(), nullptr, 6, &err), F3R_OK)
      << err.message;
  EXPECT_EQ(f3r_sim_outputs(f3r_session_sim(s.get()))->q[F3R_Q_MODAL], 1e-4);
}

// A leg pulled in at 1000 N with no stops collapses within 0.1 s: the step fails, and the
// session is as it was before it, sensors included; a later run equals a clean session's.
TEST(Session, AFailedStepIsUndoneBitForBit) {
  auto s = Open(kSensorScene);
  auto clean = Open(kSensorScene);
  f3r_error err{};
  const int nq = f3r_model_nq(f3r_session_model(s.get()));
  auto push = Forces(s.get(), {{F3R_Q_RHO, 3.0}, {F3R_Q_THETA + 1, 0.2}});
  for (f3r_session* x : {s.get(), clean.get()})
    ASSERT_EQ(f3r_session_step(x, push.data(), nq, 7, 1e-3, &err), F3R_OK) << err.message;
  const auto before = Snapshot(s.get());
  ASSERT_TRUE(SameBits(before, Snapshot(clean.get())));

  auto collapse = Forces(s.get(), {{F3R_Q_RHO, -1000.0}});
  EXPECT_NE(f3r_session_step(s.get(), collapse.data(), nq, 200, 1e-3, &err), F3R_OK);
  EXPECT_GT(std::strlen(err.message), 0u);
  EXPECT_TRUE(SameBits(Snapshot(s.get()), before)) << "the failed step left marks: " << err.message;

  // The run goes on from there as the clean one does (a new command restarts both).
  auto next = Forces(s.get(), {{F3R_Q_RHO + 1, -4.0}});
  for (f3r_session* x : {s.get(), clean.get()})
    ASSERT_EQ(f3r_session_step(x, next.data(), nq, 25, 1e-3, &err), F3R_OK) << err.message;
  EXPECT_TRUE(SameBits(Snapshot(s.get()), Snapshot(clean.get())));
  // and after a reset, too
  for (f3r_session* x : {s.get(), clean.get()}) {
    ASSERT_EQ(f3r_session_reset(x, &err), F3R_OK) << err.message;
    ASSERT_EQ(f3r_session_step(x, push.data(), nq, 30, 1e-3, &err), F3R_OK) << err.message;
  }
  EXPECT_TRUE(SameBits(Snapshot(s.get()), Snapshot(clean.get())));
}

// f3r_sim_restore puts a run back at a saved state: the same outputs, and a run on from there
// equals the run from the first time it was there.
TEST(Session, ASnapshotRestoresTheRun) {
  auto s = Open(kSensorScene);
  f3r_sim* sim = f3r_session_sim(s.get());
  f3r_error err{};
  const int nq = f3r_model_nq(f3r_session_model(s.get()));
  auto push = Forces(s.get(), {{F3R_Q_RHO + 2, 8.0}});
  ASSERT_EQ(f3r_session_step(s.get(), push.data(), nq, 4, 1e-3, &err), F3R_OK);
  f3r_sim_snapshot* raw = nullptr;
  ASSERT_EQ(f3r_sim_snapshot_create(sim, &raw, &err), F3R_OK);
  std::unique_ptr<f3r_sim_snapshot, void (*)(f3r_sim_snapshot*)> snap(raw,
                                                                      f3r_sim_snapshot_destroy);
  const f3r_outputs at = *f3r_sim_outputs(sim);
  auto other = Forces(s.get(), {{F3R_Q_RHO, -6.0}});
  ASSERT_EQ(f3r_sim_set_forces(sim, other.data(), &err), F3R_OK);
  ASSERT_EQ(f3r_sim_advance(sim, 0.02, &err), F3R_OK);
  const f3r_outputs first = *f3r_sim_outputs(sim);
  ASSERT_EQ(f3r_sim_restore(sim, snap.get(), &err), F3R_OK) << err.message;
  const f3r_outputs back = *f3r_sim_outputs(sim);
  EXPECT_EQ(back.t, at.t);
  EXPECT_EQ(std::memcmp(back.q, at.q, sizeof(double) * static_cast<size_t>(nq)), 0);
  EXPECT_EQ(std::memcmp(back.v, at.v, sizeof(double) * static_cast<size_t>(nq)), 0);
  EXPECT_EQ(std::memcmp(back.actuator, at.actuator, sizeof at.actuator), 0);
  ASSERT_EQ(f3r_sim_set_forces(sim, other.data(), &err), F3R_OK);
  ASSERT_EQ(f3r_sim_advance(sim, 0.02, &err), F3R_OK);
  EXPECT_EQ(std::memcmp(f3r_sim_outputs(sim)->q, first.q, sizeof(double) * static_cast<size_t>(nq)),
            0);
}

// The closed-loop measurement is the largest end-effector distance from the check configuration
// run alone on the same commands; the run itself is unchanged by it.
TEST(Session, AClosedLoopMeasuresItsDistanceFromTheCheck) {
  const std::string scene = ScenePath("rest_turned.yaml");
  auto s = Open(scene, {"accuracy.end_effector=1e-5"});
  auto plain = Open(scene, {"accuracy.end_effector=1e-5", "accuracy.verify=false"});
  double measured = -1.0;
  int met = 0;
  const char* lost = nullptr;
  ASSERT_EQ(f3r_session_measurement(plain.get(), &measured, &met, &lost), 0);
  ASSERT_EQ(f3r_session_measurement(s.get(), &measured, &met, &lost), 1);
  EXPECT_EQ(measured, 0.0);
  // the check, built here from the session's resolved scene
  f3r_scene check_scene;
  ASSERT_EQ(f3r_accuracy_check_scene(f3r_session_scene(s.get()), 0, &check_scene), 1);
  auto check_model = MakeModel(check_scene);
  f3r_solver_settings settings = f3r_solver_settings_from_scene(&check_scene);
  settings.stop_at_outputs = 1;
  f3r_sim* raw = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_sim_create(check_model.get(), &settings, &raw, &err), F3R_OK) << err.message;
  SimPtr check(raw);
  const int nq = f3r_model_nq(f3r_session_model(s.get()));
  std::vector<double> check_held(F3R_MAX_Q, 0.0);
  double largest = 0.0;
  for (int k = 1; k <= 60; ++k) {
    auto u = Forces(s.get(), {{F3R_Q_RHO, k < 15 ? 30.0 : 0.0}, {F3R_Q_THETA + 2, 0.05}});
    for (f3r_session* x : {s.get(), plain.get()})
      ASSERT_EQ(f3r_session_step(x, u.data(), nq, 1, 1e-3, &err), F3R_OK) << err.message;
    for (int n = 0; n < F3R_Q_MODAL; ++n)
      check_held[static_cast<size_t>(n)] = u[static_cast<size_t>(n)];
    ASSERT_EQ(f3r_sim_set_forces(check.get(), check_held.data(), &err), F3R_OK);
    ASSERT_EQ(f3r_sim_advance(check.get(), k * 1e-3, &err), F3R_OK) << err.message;
    const double* a = f3r_sim_outputs(f3r_session_sim(s.get()))->q;
    const double* b = f3r_sim_outputs(check.get())->q;
    largest = std::max(largest, std::hypot(a[F3R_Q_X] - b[F3R_Q_X], a[F3R_Q_Y] - b[F3R_Q_Y]));
    EXPECT_TRUE(SameBits(Snapshot(s.get()), Snapshot(plain.get()))) << "the check changed the run";
  }
  ASSERT_EQ(f3r_session_measurement(s.get(), &measured, &met, &lost), 1);
  EXPECT_EQ(measured, largest);
  EXPECT_GT(measured, 0.0);
  EXPECT_EQ(met, measured <= F3R_CHECK_MARGIN * 1e-5);
  EXPECT_STREQ(lost, "");
  ASSERT_EQ(f3r_session_reset(s.get(), &err), F3R_OK);
  ASSERT_EQ(f3r_session_measurement(s.get(), &measured, &met, &lost), 1);
  EXPECT_EQ(measured, 0.0);
}

// A shell that measures apart (the node, on its own thread) drives the same check to the same
// bits as a session that steps it itself; the session then neither steps nor reports it.
TEST(Session, ACheckDrivenApartMeasuresTheSameBits) {
  const std::string scene = ScenePath("rest_turned.yaml");
  auto inline_session = Open(scene, {"accuracy.end_effector=1e-5"});
  f3r_scene loaded = f3r_default_scene();
  f3r_error err{};
  const char* sets[] = {"accuracy.end_effector=1e-5"};
  const f3r_scene_options source{0.0, sets, 1};
  ASSERT_EQ(f3r_scene_load_with(scene.c_str(), &source, &loaded, &err), F3R_OK) << err.message;
  f3r_session_options options{};
  options.commanded = 1;
  options.measure_apart = 1;
  f3r_session* raw = nullptr;
  ASSERT_EQ(f3r_session_open_scene(&loaded, &options, &raw, &err), F3R_OK) << err.message;
  f3r_scene_free(&loaded);
  SessionPtr apart(raw);
  f3r_closed_loop_check* check = f3r_session_closed_loop_check(apart.get());
  ASSERT_NE(check, nullptr);
  EXPECT_EQ(f3r_session_closed_loop_check(inline_session.get()), nullptr);
  double measured = -1.0;
  int met = 0;
  ASSERT_EQ(f3r_session_measurement(apart.get(), &measured, &met, nullptr), 0);
  const int nq = f3r_model_nq(f3r_session_model(apart.get()));
  for (int k = 1; k <= 40; ++k) {
    // over the limit, as the node's summed topics may be: advance takes it, step would not
    auto u = Forces(apart.get(), {{F3R_Q_RHO, k < 10 ? 1500.0 : 0.0}, {F3R_Q_RHO + 1, -20.0}});
    ASSERT_EQ(f3r_session_advance(apart.get(), u.data(), nq, 1e-3, &err), F3R_OK) << err.message;
    f3r_closed_loop_check_period(check, u.data(), k * 1e-3,
                                 f3r_sim_outputs(f3r_session_sim(apart.get()))->q + F3R_Q_X);
    if (k < 10) {
      EXPECT_EQ(f3r_session_step(inline_session.get(), u.data(), nq, 1, 1e-3, &err),
                F3R_ERR_ARGUMENT);
      EXPECT_NE(std::string(err.message).find("leg_force_1"), std::string::npos) << err.message;
    }
    ASSERT_EQ(f3r_session_advance(inline_session.get(), u.data(), nq, 1e-3, &err), F3R_OK);
    EXPECT_TRUE(SameBits(Snapshot(apart.get()), Snapshot(inline_session.get())));
  }
  const char* lost = nullptr;
  ASSERT_EQ(f3r_session_measurement(inline_session.get(), &measured, &met, &lost), 1);
  int apart_met = 0;
  EXPECT_EQ(f3r_closed_loop_check_measured(check, &apart_met, &lost), measured);
  EXPECT_GT(measured, 0.0);
  EXPECT_EQ(apart_met, met);
  EXPECT_EQ(f3r_closed_loop_check_request(check), 1e-5);
  // reset and set_state leave an apart check to its shell
  f3r_closed_loop_check_lose(check, "the run stopped");
  EXPECT_TRUE(std::isnan(f3r_closed_loop_check_measured(check, nullptr, &lost)));
  EXPECT_STREQ(lost, "the run stopped");
  ASSERT_EQ(f3r_session_reset(apart.get(), &err), F3R_OK);
  EXPECT_TRUE(std::isnan(f3r_closed_loop_check_measured(check, nullptr, nullptr)));
  ASSERT_EQ(f3r_closed_loop_check_reset(check, &err), F3R_OK);
  EXPECT_EQ(f3r_closed_loop_check_measured(check, nullptr, &lost), 0.0);
  EXPECT_STREQ(lost, "");
}

// advance checks only the count and finiteness, naming them, and changes nothing on a refusal.
TEST(Session, AdvanceRefusesWrongCountsAndValuesThatAreNotFinite) {
  auto s = Open(kSensorScene);
  const auto before = Snapshot(s.get());
  f3r_error err{};
  auto u = Forces(s.get());
  const int nq = static_cast<int>(u.size());
  EXPECT_EQ(f3r_session_advance(s.get(), u.data(), nq - 1, 1e-3, &err), F3R_ERR_ARGUMENT);
  EXPECT_NE(std::string(err.message).find("expected"), std::string::npos) << err.message;
  u[2] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(f3r_session_advance(s.get(), u.data(), nq, 1e-3, &err), F3R_ERR_ARGUMENT);
  EXPECT_NE(std::string(err.message).find("forces[2]"), std::string::npos) << err.message;
  u[2] = 0.0;
  EXPECT_EQ(f3r_session_advance(s.get(), u.data(), nq, 0.0, &err), F3R_ERR_ARGUMENT);
  EXPECT_TRUE(SameBits(before, Snapshot(s.get())));
}

// Commands from outside: the knob never says that nothing excites a scene at rest; it sizes the
// model for the command limits, or for the excitation the scene states, and a larger
// excitation never gets fewer modes.
TEST(Session, ACommandedChoiceIsSizedForTheCommandsNotForRest) {
  const std::string scene = ScenePath("rest_turned.yaml");
  const char* open_modes = "links={model: fixed_free, damping_ratio: 0.01}";
  auto limits = Open(scene, {open_modes, "accuracy.end_effector=1e-6", "accuracy.verify=false"});
  auto stated = Open(scene, {open_modes, "accuracy.end_effector=1e-6", "accuracy.verify=false",
                             "accuracy.excitation=20"});
  f3r_session_options scripted{};
  const char* sets[] = {open_modes, "accuracy.end_effector=1e-6", "accuracy.verify=false"};
  scripted.overrides = sets;
  scripted.override_count = 3;
  f3r_session* raw = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_session_open(scene.c_str(), &scripted, &raw, &err), F3R_OK) << err.message;
  SessionPtr at_rest(raw);
  const std::string said = f3r_session_choice(limits.get())->summary;
  EXPECT_EQ(said.find("nothing excites"), std::string::npos) << said;
  EXPECT_NE(said.find("leg-force steps of 1000 N"), std::string::npos) << said;
  EXPECT_NE(std::string(f3r_session_choice(stated.get())->summary).find("steps of 20 N"),
            std::string::npos);
  EXPECT_NE(std::string(f3r_session_choice(at_rest.get())->summary).find("nothing excites"),
            std::string::npos);
  for (int i = 0; i < 3; ++i) {
    const int big = f3r_session_choice(limits.get())->modes[i];
    const int small = f3r_session_choice(stated.get())->modes[i];
    const int rest = f3r_session_choice(at_rest.get())->modes[i];
    EXPECT_GE(big, small) << "link " << i;
    EXPECT_GE(small, rest) << "link " << i;
    EXPECT_GT(big, rest) << "link " << i;
  }
  // the scene's own inputs stay its own: the excitation is the knob's alone
  for (int k = 0; k < F3R_RIGID_FORCES; ++k)
    EXPECT_EQ(f3r_session_scene(limits.get())->inputs[k].kind, F3R_INPUT_NONE);
}

}  // namespace

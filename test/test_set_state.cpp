// f3r_sim_set_state: the state it sets is consistent and reads back exactly, the run continues
// from it with a fresh energy balance, setting the scene's initial state is a reset, and every
// refusal leaves the simulation bit for bit as it was.
#include <gtest/gtest.h>

#include <cstring>

#include "queries.h"
#include "test_support.h"

namespace {

SimPtr MakeSim(const f3r_model* m, f3r_formulation form, double rtol = 1e-9) {
  f3r_solver_settings set = f3r_solver_settings_from_scene(&m->scene);
  set.formulation = form;
  set.rtol = rtol;
  set.atol = rtol * 1e-2;
  f3r_sim* raw = nullptr;
  f3r_error err{};
  if (f3r_sim_create(m, &set, &raw, &err) != F3R_OK) throw std::runtime_error(err.message);
  return SimPtr(raw);
}

std::vector<double> State(const f3r_sim* s) {
  const int ny = f3r_state_size(f3r_sim_model(s), f3r_sim_formulation(s));
  const double* y = f3r_sim_state(s);
  return std::vector<double>(y, y + ny);
}

// Bitwise equality of two vectors of doubles (NaN-safe, -0 != +0).
bool SameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// One link of each kind (rigid, fixed-pinned r = 3, fixed-free r = 2), no inputs.
f3r_scene MixedScene() {
  return SceneWithLinks(F3R_LINK_RIGID, 0, F3R_LINK_FIXED_PINNED, 3, F3R_LINK_FIXED_FREE, 2);
}

class SetState : public ::testing::TestWithParam<f3r_formulation> {};

TEST_P(SetState, IsConsistentReadsBackExactlyAndRestartsTheEnergyBalance) {
  auto m = MakeModel(MixedScene());
  const int n_modal = m->nq - F3R_Q_MODAL;
  ASSERT_EQ(n_modal, 5);
  auto sim = MakeSim(m.get(), GetParam());
  f3r_error err{};
  // Somewhere along a run with a held force, which set_state keeps.
  std::vector<double> held(F3R_MAX_Q, 0.0);
  held[F3R_FORCE_RHO + 1] = 2.0;
  ASSERT_EQ(f3r_sim_set_forces(sim.get(), held.data(), &err), F3R_OK) << err.message;
  ASSERT_EQ(f3r_sim_advance(sim.get(), 0.004, &err), F3R_OK) << err.message;
  held[F3R_FORCE_RHO + 1] = 0.0;  // the unforced run from the new state
  ASSERT_EQ(f3r_sim_set_forces(sim.get(), held.data(), &err), F3R_OK) << err.message;
  const double t_before = f3r_sim_time(sim.get());

  const double pose[3] = {0.012, -0.007, 0.05};
  const double twist[3] = {0.15, -0.1, 2.0};
  const double modal[5] = {2e-4, -1e-5, 3e-6, -3e-4, 2e-5};
  const double modal_rate[5] = {0.05, -0.01, 0.002, 0.08, -0.003};
  ASSERT_EQ(f3r_sim_set_state(sim.get(), pose, twist, modal, modal_rate, &err), F3R_OK)
      << err.message;
  EXPECT_EQ(f3r_sim_time(sim.get()), t_before);
  const f3r_outputs* o = f3r_sim_outputs(sim.get());
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(o->q[F3R_Q_X + k], pose[k]) << k;
    EXPECT_EQ(o->v[F3R_Q_X + k], twist[k]) << k;
  }
  for (int k = 0; k < n_modal; ++k) {
    EXPECT_EQ(o->q[F3R_Q_MODAL + k], modal[k]) << k;
    EXPECT_EQ(o->v[F3R_Q_MODAL + k], modal_rate[k]) << k;
  }
  // The loops close to rounding (lengths ~0.3 m, so 1e-15 m is a few ulps).
  EXPECT_LT(o->constraint_residual, 1e-15);
  EXPECT_LT(o->velocity_residual, 1e-14);
  // The tip deflections of the links given above: rigid none, fixed-pinned none, fixed-free
  // sum psi_j(1) eta_j with psi_j(1) = 2 (-1)^j (docs/model.md).
  EXPECT_EQ(o->tip_deflection[0], 0.0);
  EXPECT_EQ(o->tip_deflection[1], 0.0);
  EXPECT_NEAR(o->tip_deflection[2], -2.0 * modal[3] + 2.0 * modal[4], 1e-15);
  EXPECT_EQ(o->external_work, 0.0);
  const double energy = o->kinetic_energy + o->potential_energy;
  EXPECT_LT(o->energy_balance_error, 1e-14 * energy);

  // Unforced from here: T + V is conserved up to the integrator's error, as in the same run
  // started by a scene with these initial values at t = 0 (the motion is autonomous).
  f3r_scene from_scene = MixedScene();
  for (int k = 0; k < 3; ++k) {
    from_scene.platform_pose0[k] = pose[k];
    from_scene.platform_velocity0[k] = twist[k];
  }
  for (int i = 0, k = 0; i < 3; ++i)
    for (int j = 0; j < m->link[i].modes; ++j, ++k) {
      from_scene.links[i].eta0[j] = modal[k];
      from_scene.links[i].eta_rate0[j] = modal_rate[k];
    }
  auto m2 = MakeModel(from_scene);
  auto reference = MakeSim(m2.get(), GetParam());
  double worst = 0.0, worst_reference = 0.0;
  for (int k = 1; k <= 40; ++k) {
    ASSERT_EQ(f3r_sim_advance(sim.get(), t_before + 1e-3 * k, &err), F3R_OK) << err.message;
    ASSERT_EQ(f3r_sim_advance(reference.get(), 1e-3 * k, &err), F3R_OK) << err.message;
    o = f3r_sim_outputs(sim.get());
    const f3r_outputs* r = f3r_sim_outputs(reference.get());
    worst = std::max(worst, o->energy_balance_error);
    worst_reference = std::max(worst_reference, r->energy_balance_error);
    EXPECT_LT(o->constraint_residual, 1e-9);
    for (int n = 0; n < m->nq; ++n)
      EXPECT_NEAR(o->q[n], r->q[n], 1e-7) << n << " at " << k << " ms";
  }
  // BDF's numerical damping of the fixed-pinned link's modes (rtol 1e-9) is ~1e-6 of T + V here.
  EXPECT_LT(worst, 1e-5 * energy) << "T + V = " << energy << " J";
  EXPECT_LT(worst, 2.0 * worst_reference + 1e-12 * energy);
  std::printf(
      "set_state, 40 ms unforced: energy balance error %.3e J of T + V %.3e J "
      "(%.3e J from the scene's initial state)\n",
      worst, energy, worst_reference);
}

// The actuator lag states are state, not pose: set_state keeps them.
TEST_P(SetState, KeepsTheActuatorLagStates) {
  f3r_scene s;
  f3r_error err{};
  ASSERT_EQ(f3r_scene_load((std::string(F3R_SOURCE_DIR) + "/test/scenes/all_effects.yaml").c_str(),
                           &s, &err),
            F3R_OK)
      << err.message;
  auto m = MakeModel(s);
  ASSERT_EQ(m->n_lag, 3);
  auto sim = MakeSim(m.get(), GetParam());
  ASSERT_EQ(f3r_sim_advance(sim.get(), 0.01, &err), F3R_OK) << err.message;
  const int lag = f3r_lag_index(m.get(), GetParam());
  const std::vector<double> before = State(sim.get());
  ASSERT_GT(std::fabs(before[lag]), 1.0);  // the step on rho_1 has come through in part
  const double pose[3] = {0.0, 0.01, 0.0}, twist[3] = {0.0, 0.0, 0.0};
  ASSERT_EQ(f3r_sim_set_state(sim.get(), pose, twist, nullptr, nullptr, &err), F3R_OK)
      << err.message;
  const std::vector<double> after = State(sim.get());
  for (int i = 0; i < 3; ++i) EXPECT_EQ(after[lag + i], before[lag + i]) << "leg " << i + 1;
  const f3r_outputs* o = f3r_sim_outputs(sim.get());
  for (int k = F3R_Q_MODAL; k < m->nq; ++k) {
    EXPECT_EQ(o->q[k], 0.0);
    EXPECT_EQ(o->v[k], 0.0);
  }
  ASSERT_EQ(f3r_sim_advance(sim.get(), 0.02, &err), F3R_OK) << err.message;
}

// Setting the scene's own initial state at t = 0 is what a reset does: the same run to the bit.
TEST_P(SetState, TheScenesInitialStateGivesTheResetRun) {
  f3r_scene s =
      SceneWithLinks(F3R_LINK_FIXED_FREE, 2, F3R_LINK_FIXED_PINNED, 2, F3R_LINK_FIXED_FREE, 1);
  s.platform_pose0[0] = 0.01;
  s.platform_pose0[2] = -0.1;
  s.platform_velocity0[1] = 0.2;
  s.platform_velocity0[2] = 1.5;
  s.links[0].eta0[0] = 1e-4;
  s.links[1].eta_rate0[1] = 0.01;
  s.links[2].eta0[0] = -5e-5;
  auto m = MakeModel(s);
  f3r_error err{};
  auto reset = MakeSim(m.get(), GetParam());
  ASSERT_EQ(f3r_sim_advance(reset.get(), 0.003, &err), F3R_OK) << err.message;
  ASSERT_EQ(f3r_sim_reset(reset.get(), &err), F3R_OK) << err.message;
  auto set = MakeSim(m.get(), GetParam());
  std::vector<double> modal, rate;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < m->link[i].modes; ++j) {
      modal.push_back(s.links[i].eta0[j]);
      rate.push_back(s.links[i].eta_rate0[j]);
    }
  ASSERT_EQ(f3r_sim_set_state(set.get(), s.platform_pose0, s.platform_velocity0, modal.data(),
                              rate.data(), &err),
            F3R_OK)
      << err.message;
  EXPECT_TRUE(SameBits(State(reset.get()), State(set.get())));
  for (double t : {0.005, 0.02}) {
    ASSERT_EQ(f3r_sim_advance(reset.get(), t, &err), F3R_OK) << err.message;
    ASSERT_EQ(f3r_sim_advance(set.get(), t, &err), F3R_OK) << err.message;
    const auto a = State(reset.get()), b = State(set.get());
    double diff = 0.0;
    for (size_t k = 0; k < a.size(); ++k) diff = std::max(diff, std::fabs(a[k] - b[k]));
    EXPECT_TRUE(SameBits(a, b)) << "at t = " << t << ", largest difference " << diff;
  }
}

struct Snapshot {
  std::vector<double> y, q, v;
  double t, balance, work, kinetic;
};

Snapshot Take(f3r_sim* s) {
  Snapshot r;
  r.y = State(s);
  r.t = f3r_sim_time(s);
  const f3r_outputs* o = f3r_sim_outputs(s);
  const int nq = f3r_sim_model(s)->nq;
  r.q.assign(o->q, o->q + nq);
  r.v.assign(o->v, o->v + nq);
  r.balance = o->energy_balance_error;
  r.work = o->external_work;
  r.kinetic = o->kinetic_energy;
  return r;
}

void ExpectSame(const Snapshot& a, const Snapshot& b, const std::string& what) {
  EXPECT_TRUE(SameBits(a.y, b.y)) << what;
  EXPECT_TRUE(SameBits(a.q, b.q)) << what;
  EXPECT_TRUE(SameBits(a.v, b.v)) << what;
  EXPECT_EQ(std::memcmp(&a.t, &b.t, sizeof a.t), 0) << what;
  EXPECT_EQ(std::memcmp(&a.balance, &b.balance, sizeof a.balance), 0) << what;
  EXPECT_EQ(std::memcmp(&a.work, &b.work, sizeof a.work), 0) << what;
  EXPECT_EQ(std::memcmp(&a.kinetic, &b.kinetic, sizeof a.kinetic), 0) << what;
}

// Every refusal names its cause and changes nothing: the state, time and energy reference read
// the same, and the run continues exactly as a twin's that was never asked.
TEST_P(SetState, RefusalsNameTheCauseAndChangeNothing) {
  f3r_scene s =
      SceneWithLinks(F3R_LINK_FIXED_FREE, 2, F3R_LINK_FIXED_FREE, 2, F3R_LINK_FIXED_FREE, 2);
  s.end_stops = 1;
  s.stroke_min = 0.0;
  s.stroke_max = 0.2;
  s.inputs[F3R_FORCE_RHO].kind = F3R_INPUT_HARMONIC;
  s.inputs[F3R_FORCE_RHO].amplitude = 3.0;
  s.inputs[F3R_FORCE_RHO].omega = 2 * M_PI * 50.0;
  auto m = MakeModel(s);
  const int n_modal = m->nq - F3R_Q_MODAL;
  f3r_error err{};
  auto sim = MakeSim(m.get(), GetParam());
  auto twin = MakeSim(m.get(), GetParam());
  ASSERT_EQ(f3r_sim_advance(sim.get(), 0.005, &err), F3R_OK) << err.message;
  ASSERT_EQ(f3r_sim_advance(twin.get(), 0.005, &err), F3R_OK) << err.message;
  const Snapshot before = Take(sim.get());
  ASSERT_GT(before.work, 0.0);  // the energy reference is not a trivial one

  const double home[3] = {0.0, 0.0, 0.0}, still[3] = {0.0, 0.0, 0.0};
  std::vector<double> modal(n_modal, 0.0), nan_modal(n_modal, 0.0);
  nan_modal[n_modal - 1] = NAN;
  const double nan_pose[3] = {0.0, NAN, 0.0}, inf_twist[3] = {0.0, 0.0, INFINITY};
  // A_2 = (0, R_A), C_2 = P + r_PC (0, 1) at phi_p = 0: C_2 on A_2, and 0.01 m (0.05 l) from it.
  const double r_a = 0.66 / std::sqrt(3.0), r_pc = 0.1 / std::sqrt(3.0);
  const double onto_a2[3] = {0.0, r_a - r_pc, 0.0}, near_a2[3] = {0.0, r_a - r_pc - 0.01, 0.0};
  // 0.1 m away from A_1 (at -pi/6): rho_1 = 0.3233 + 0.1 - l = 0.223 m > stroke_max.
  const double past_stop[3] = {-0.1 * std::cos(M_PI / 6), 0.1 * std::sin(M_PI / 6), 0.0};
  struct Case {
    const char* name;
    const double *pose, *twist, *modal, *rate;
    f3r_status code;
    std::vector<const char*> words;
  } cases[] = {
      {"NULL pose", nullptr, still, nullptr, nullptr, F3R_ERR_ARGUMENT, {"NULL"}},
      {"NaN pose", nan_pose, still, nullptr, nullptr, F3R_ERR_ARGUMENT, {"pose[1]", "not finite"}},
      {"Inf twist", home, inf_twist, nullptr, nullptr, F3R_ERR_ARGUMENT, {"twist[2]"}},
      {"NaN modal", home, still, nan_modal.data(), nullptr, F3R_ERR_ARGUMENT, {"modal[5]"}},
      {"NaN modal rate",
       home,
       still,
       modal.data(),
       nan_modal.data(),
       F3R_ERR_ARGUMENT,
       {"modal_rate[5]"}},
      {"C_2 on A_2",
       onto_a2,
       still,
       nullptr,
       nullptr,
       F3R_ERR_SINGULAR,
       {"unreachable", "leg 2", "rho_2 + l <= 0"}},
      {"C_2 near A_2",
       near_a2,
       still,
       nullptr,
       nullptr,
       F3R_ERR_SINGULAR,
       {"unreachable", "leg 2", "collapse guard"}},
      {"past the end stop",
       past_stop,
       still,
       nullptr,
       nullptr,
       F3R_ERR_ARGUMENT,
       {"leg 1", "rho_1 = 0.223", "[0, 0.2]"}},
  };
  for (const Case& c : cases) {
    err = f3r_error{};
    EXPECT_EQ(f3r_sim_set_state(sim.get(), c.pose, c.twist, c.modal, c.rate, &err), c.code)
        << c.name;
    for (const char* w : c.words)
      EXPECT_NE(std::strstr(err.message, w), nullptr)
          << c.name << ": '" << err.message << "' lacks '" << w << "'";
    ExpectSame(before, Take(sim.get()), c.name);
  }
  ASSERT_EQ(f3r_sim_advance(sim.get(), 0.02, &err), F3R_OK) << err.message;
  ASSERT_EQ(f3r_sim_advance(twin.get(), 0.02, &err), F3R_OK) << err.message;
  ExpectSame(Take(twin.get()), Take(sim.get()), "the run after the refusals");
}

INSTANTIATE_TEST_SUITE_P(BothFormulations, SetState,
                         ::testing::Values(F3R_FORMULATION_DAE, F3R_FORMULATION_MINIMAL),
                         [](const ::testing::TestParamInfo<f3r_formulation>& info) {
                           return std::string(info.param == F3R_FORMULATION_DAE ? "dae"
                                                                                : "minimal");
                         });

}  // namespace

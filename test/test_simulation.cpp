// Whole runs against physical laws and closed-form results: energy balance, constraint drift,
// agreement of the two formulations, paper simulation 1's geometry, and limiting cases.
#include <gtest/gtest.h>

#include <cstring>
#include <map>

#include "flex3rpr/modal.h"
#include "queries.h"
#include "erk_tables.h"
#include "stepper.h" /* before the ARKODE headers: it includes stdio.h, which they need */
#include "test_support.h"

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_butcher_erk.h>
#include <arkode/arkode_erkstep.h>

namespace {

struct Sample {
  double t;
  std::vector<double> q;
  double energy;      // T + V - W
  double mechanical;  // T + V
  double constraint;
};

struct RunResult {
  std::vector<Sample> samples;
  f3r_sim_stats stats;
};

RunResult RunScene(const f3r_scene& scene, double output_step, double duration) {
  auto m = MakeModel(scene);
  f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
  f3r_sim* raw = nullptr;
  f3r_error err{};
  if (f3r_sim_create(m.get(), &set, &raw, &err) != F3R_OK) throw std::runtime_error(err.message);
  SimPtr sim(raw);
  RunResult r;
  const long n = std::lround(duration / output_step);
  for (long k = 0; k <= n; ++k) {
    if (k > 0 && f3r_sim_advance(sim.get(), k * output_step, &err) != F3R_OK)
      throw std::runtime_error(err.message);
    const f3r_outputs* o = f3r_sim_outputs(sim.get());
    Sample s;
    s.t = o->t;
    s.q.assign(o->q, o->q + m->nq);
    s.mechanical = o->kinetic_energy + o->potential_energy;
    s.energy = s.mechanical - o->external_work;
    s.constraint = o->constraint_residual;
    r.samples.push_back(s);
  }
  r.stats = f3r_sim_outputs(sim.get())->stats;
  return r;
}

// (x_p, y_p) at `outputs` outputs `step` apart, and the run's final counts.
std::vector<double> PlatformPath(const f3r_model* m, const f3r_solver_settings& set, int outputs,
                                 double step, f3r_sim_stats* stats) {
  f3r_sim* raw = nullptr;
  f3r_error err{};
  if (f3r_sim_create(m, &set, &raw, &err) != F3R_OK) throw std::runtime_error(err.message);
  SimPtr sim(raw);
  std::vector<double> path;
  for (int k = 1; k <= outputs; ++k) {
    if (f3r_sim_advance(sim.get(), k * step, &err) != F3R_OK) throw std::runtime_error(err.message);
    const f3r_outputs* o = f3r_sim_outputs(sim.get());
    path.push_back(o->q[F3R_Q_X]);
    path.push_back(o->q[F3R_Q_Y]);
    *stats = o->stats;
  }
  return path;
}

f3r_scene Scene(const std::string& name) {
  f3r_scene s;
  f3r_error err{};
  if (f3r_scene_load(ScenePath(name).c_str(), &s, &err) != F3R_OK)
    throw std::runtime_error(err.message);
  return s;
}

class FreeVibration : public ::testing::TestWithParam<std::tuple<f3r_link_model, f3r_formulation>> {
};

double FreeVibrationDrift(f3r_link_model model, f3r_formulation form, double rtol, long* steps,
                          bool corrected = false) {
  f3r_scene s = f3r_default_scene();
  for (int i = 0; i < 3; ++i) {
    s.links[i].model = model;
    s.links[i].modes = corrected ? 1 : 2;  // 1 mode + the static shapes: links[1].eta0[1] a shape
    s.links[i].static_correction = corrected;
  }
  s.links[0].eta0[0] = 1e-3;
  s.links[1].eta0[1] = -2e-4;
  s.formulation = form;
  s.rtol = rtol;
  s.atol = rtol * 1e-2;
  RunResult r = RunScene(s, 1e-3, 0.2);
  const double e0 = r.samples[0].mechanical;
  double worst = 0.0;
  for (const auto& x : r.samples) worst = std::max(worst, std::fabs(x.mechanical - e0) / e0);
  *steps = r.stats.steps;
  return worst;
}

// T + V is conserved up to BDF's numerical damping of the resolved oscillations, which grows
// linearly in time and shrinks with the tolerance. A missing or wrong term (the appendix's
// F_c_eta) instead drifts by percent in 0.05 s whatever the tolerance.
TEST_P(FreeVibration, ConservesMechanicalEnergyUpToTheIntegratorsDamping) {
  const auto model = std::get<0>(GetParam());
  const auto form = std::get<1>(GetParam());
  long steps_loose = 0, steps_tight = 0;
  // rtol 1e-10, not tighter: the dae formulation's Newton iteration can fail below
  // (docs/solvers.md).
  const double loose = FreeVibrationDrift(model, form, 1e-8, &steps_loose);
  const double tight = FreeVibrationDrift(model, form, 1e-10, &steps_tight);
  EXPECT_LT(tight, 3e-6) << "relative drift of T + V over 0.2 s, " << steps_tight << " steps";
  EXPECT_LT(tight, loose / 20.0) << "the drift must shrink with the tolerance: " << loose
                                 << " at rtol 1e-8";
  RecordProperty("drift_rtol_1e-8", std::to_string(loose));
  RecordProperty("drift_rtol_1e-10", std::to_string(tight));
  std::printf("free vibration drift over 0.2 s: %.3e at rtol 1e-8, %.3e at rtol 1e-10\n", loose,
              tight);
}

// The same with the static correction: its shapes are stiff (the first fixed-free one near
// 30 alpha_1^4), so this also checks the solver keeps T + V through them.
TEST_P(FreeVibration, ConservesMechanicalEnergyWithTheStaticCorrection) {
  const auto model = std::get<0>(GetParam());
  const auto form = std::get<1>(GetParam());
  long steps_loose = 0, steps_tight = 0;
  const double loose = FreeVibrationDrift(model, form, 1e-8, &steps_loose, true);
  const double tight = FreeVibrationDrift(model, form, 1e-10, &steps_tight, true);
  EXPECT_LT(tight, 3e-6) << "relative drift of T + V over 0.2 s, " << steps_tight << " steps";
  EXPECT_LT(tight, loose / 20.0) << "the drift must shrink with the tolerance: " << loose
                                 << " at rtol 1e-8";
  std::printf("corrected free vibration drift over 0.2 s: %.3e at rtol 1e-8, %.3e at 1e-10\n",
              loose, tight);
}

INSTANTIATE_TEST_SUITE_P(
    BothEndsBothFormulations, FreeVibration,
    ::testing::Combine(::testing::Values(F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_FREE),
                       ::testing::Values(F3R_FORMULATION_DAE, F3R_FORMULATION_MINIMAL)));

class PaperRun : public ::testing::TestWithParam<const char*> {};

TEST_P(PaperRun, DaeKeepsConstraintsAndEnergyBalance) {
  f3r_scene s = Scene(GetParam());
  s.formulation = F3R_FORMULATION_DAE;
  s.rtol = 1e-10;
  s.atol = 1e-12;
  RunResult r = RunScene(s, 1e-3, s.duration);
  double worst_constraint = 0.0, worst_energy = 0.0, scale = 0.0;
  for (const auto& x : r.samples) {
    worst_constraint = std::max(worst_constraint, x.constraint);
    worst_energy = std::max(worst_energy, std::fabs(x.energy - r.samples[0].energy));
    scale = std::max(scale, x.mechanical);
  }
  EXPECT_LE(worst_constraint, 1e-10) << GetParam();
  EXPECT_LE(worst_energy, 1e-8 * scale) << GetParam() << ": T + V - W drifts";
}

TEST_P(PaperRun, FormulationsAgreeOnPlatformPosition) {
  f3r_scene s = Scene(GetParam());
  s.rtol = 1e-10;
  s.atol = 1e-12;
  s.formulation = F3R_FORMULATION_DAE;
  RunResult dae = RunScene(s, 1e-3, s.duration);
  s.formulation = F3R_FORMULATION_MINIMAL;
  RunResult minimal = RunScene(s, 1e-3, s.duration);
  ASSERT_EQ(dae.samples.size(), minimal.samples.size());
  double worst = 0.0;
  for (size_t k = 0; k < dae.samples.size(); ++k)
    worst = std::max(worst, std::hypot(dae.samples[k].q[6] - minimal.samples[k].q[6],
                                       dae.samples[k].q[7] - minimal.samples[k].q[7]));
  EXPECT_LE(worst, 1e-8) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(AllFour, PaperRun,
                         ::testing::Values("paper_sim1.yaml", "paper_sim2.yaml",
                                           "paper_sim3_fixed_pinned.yaml",
                                           "paper_sim3_fixed_free.yaml"));

TEST(PaperSimulation1, SymmetricStraightPathAndMinimumStroke) {
  f3r_scene s = Scene("paper_sim1.yaml");
  s.formulation = F3R_FORMULATION_MINIMAL;
  s.rtol = 1e-11;
  s.atol = 1e-13;
  RunResult r = RunScene(s, 1e-4, s.duration);
  const double ux = std::cos(150.0 * M_PI / 180.0), uy = std::sin(150.0 * M_PI / 180.0);
  double worst_symmetry = 0.0, worst_offline = 0.0, rho2_min = 1e9, travel_at_min = 0.0;
  for (const auto& x : r.samples) {
    worst_symmetry = std::max(worst_symmetry, std::fabs(x.q[1] - x.q[2]));
    worst_offline = std::max(worst_offline, std::fabs(-uy * x.q[6] + ux * x.q[7]));
    if (x.q[1] < rho2_min) {
      rho2_min = x.q[1];
      travel_at_min = ux * x.q[6] + uy * x.q[7];
    }
  }
  EXPECT_LE(worst_symmetry, 1e-12) << "rho_2 = rho_3";
  EXPECT_LE(worst_offline, 1e-12) << "P leaves the line at 150 degrees from +X";
  const auto& last = r.samples.back();
  EXPECT_GT(ux * last.q[6] + uy * last.q[7], 0.1) << "P moves towards A2A3";
  // C2 reaches line A2A3 when P has travelled R_A/2 - r_PC/2 = 0.28/sqrt(3) m; there
  // |C2 - A2| = 0.28 m, so rho_2 = 0.08 m, and rho_2 grows again afterwards.
  EXPECT_NEAR(rho2_min, 0.08, 1e-7);
  EXPECT_NEAR(travel_at_min, 0.28 / std::sqrt(3.0), 2e-4);
  EXPECT_GT(last.q[1], rho2_min + 1e-3);
}

TEST(ClosedFormLimits, HeavySurroundingsGiveFixedPinnedBeamFrequencies) {
  f3r_scene s = f3r_default_scene();
  for (int i = 0; i < 3; ++i) {
    s.links[i].model = F3R_LINK_FIXED_PINNED;
    s.links[i].modes = 3;
  }
  s.cylinder_density *= 1e7;
  s.platform_mass *= 1e7;
  auto m = MakeModel(s);
  double hz[F3R_MAX_Q];
  int count = 0;
  f3r_error err{};
  ASSERT_EQ(f3r_modal_frequencies(m.get(), hz, &count, &err), F3R_OK) << err.message;
  ASSERT_EQ(count, 12);
  const double rho_a = m->link_mass / m->link_length, l = m->link_length;
  for (int k = 3; k < 12; ++k) {
    const int j = (k - 3) / 3;
    const double alpha = m->link[0].alpha[j];
    const double expected =
        alpha * alpha * std::sqrt(m->bending_stiffness / (rho_a * l * l * l * l)) / (2 * M_PI);
    EXPECT_NEAR(hz[k], expected, 1e-3 * expected) << "mode " << k;
  }
  EXPECT_NEAR(hz[3], 869.7, 0.5) << "docs/model.md's first fixed-pinned frequency";
}

TEST(ClosedFormLimits, VeryStiffLinksFollowTheRigidModel) {
  f3r_scene rigid = Scene("paper_sim3_fixed_free.yaml");
  for (int i = 0; i < 3; ++i) {
    rigid.links[i].model = F3R_LINK_RIGID;
    rigid.links[i].modes = 0;
  }
  rigid.rtol = 1e-8;
  rigid.atol = 1e-10;
  f3r_scene flexible = Scene("paper_sim3_fixed_free.yaml");
  flexible.formulation = F3R_FORMULATION_MINIMAL;
  flexible.rtol = 1e-8;
  flexible.atol = 1e-10;
  const double duration = 0.02;
  RunResult r0 = RunScene(rigid, 1e-3, duration);
  RunResult r1 = RunScene(flexible, 1e-3, duration);
  flexible.link_youngs_modulus *= 1e6;
  RunResult r2 = RunScene(flexible, 1e-3, duration);
  double nominal = 0.0, stiff = 0.0;
  for (size_t k = 0; k < r0.samples.size(); ++k) {
    nominal = std::max(nominal, std::hypot(r1.samples[k].q[6] - r0.samples[k].q[6],
                                           r1.samples[k].q[7] - r0.samples[k].q[7]));
    stiff = std::max(stiff, std::hypot(r2.samples[k].q[6] - r0.samples[k].q[6],
                                       r2.samples[k].q[7] - r0.samples[k].q[7]));
  }
  EXPECT_GT(nominal, 1e-5) << "the nominal flexible links differ visibly from rigid";
  EXPECT_LT(stiff, 1e-4 * nominal) << "E x 1e6 should approach the rigid trajectory";
  std::printf("max |P - P_rigid| over %.2f s: %.3e m nominal, %.3e m with E x 1e6\n", duration,
              nominal, stiff);
}

TEST(Simulation, TwoSimulationsShareOneModelIndependently) {
  f3r_scene s = Scene("paper_sim3_fixed_free.yaml");
  auto m = MakeModel(s);
  f3r_solver_settings set = f3r_solver_settings_from_scene(&s);
  f3r_sim *a = nullptr, *b = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_sim_create(m.get(), &set, &a, &err), F3R_OK);
  ASSERT_EQ(f3r_sim_create(m.get(), &set, &b, &err), F3R_OK);
  SimPtr sa(a), sb(b);
  std::vector<double> held(m->nq, 0.0);
  held[0] = 10.0;
  ASSERT_EQ(f3r_sim_set_forces(sb.get(), held.data(), &err), F3R_OK);
  ASSERT_EQ(f3r_sim_advance(sa.get(), 0.01, &err), F3R_OK);
  ASSERT_EQ(f3r_sim_advance(sb.get(), 0.01, &err), F3R_OK);
  const double xa = f3r_sim_outputs(sa.get())->q[6], xb = f3r_sim_outputs(sb.get())->q[6];
  EXPECT_NE(xa, xb);
  // A run of a alone gives the same as a run interleaved with b.
  f3r_sim* c = nullptr;
  ASSERT_EQ(f3r_sim_create(m.get(), &set, &c, &err), F3R_OK);
  SimPtr sc(c);
  ASSERT_EQ(f3r_sim_advance(sc.get(), 0.01, &err), F3R_OK);
  EXPECT_EQ(f3r_sim_outputs(sc.get())->q[6], xa);
}

// The outputs of one forward pass against the queries of queries.h at the output state:
// the loop forces against an LU solve of the whole constrained system [M -G^T; G 0] (the
// minimal formulation's come from its accelerations y', so they agree to the solver's
// tolerance; the dae's are its state), energies, deflections and constraint residuals.
TEST(Simulation, OutputsAgreeWithTheStagesAtTheOutputState) {
  for (f3r_formulation form : {F3R_FORMULATION_MINIMAL, F3R_FORMULATION_DAE}) {
    f3r_scene s = Scene("paper_sim3_fixed_free.yaml");
    s.gravity[1] = -9.81;  // in plane, so that gravity's forces are among the outputs
    auto m = MakeModel(s);
    f3r_solver_settings set = f3r_solver_settings_from_scene(&s);
    set.formulation = form;
    set.rtol = 1e-10;
    set.atol = 1e-12;
    f3r_sim* raw = nullptr;
    f3r_error err{};
    ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    ASSERT_EQ(f3r_sim_advance(sim.get(), 0.0123, &err), F3R_OK) << err.message;
    const f3r_outputs* o = f3r_sim_outputs(sim.get());
    const int nq = m->nq;
    std::vector<double> Q(nq), a(nq), lambda(F3R_NCON),
        work(f3r_solve_accelerations_work_size(m.get()));
    f3r_applied_forces(m.get(), o->t, nullptr, o->q, o->v, nullptr, Q.data(), nullptr);
    for (int n = 0; n < nq; ++n)
      EXPECT_NEAR(o->forces[n], Q[n], 1e-12 * (1.0 + std::fabs(Q[n]))) << n;
    ASSERT_EQ(f3r_solve_accelerations(m.get(), o->q, o->v, Q.data(), a.data(), lambda.data(),
                                      work.data()),
              F3R_OK);
    double scale = 0.0;
    for (double l : lambda) scale = std::max(scale, std::fabs(l));
    for (int c = 0; c < F3R_NCON; ++c)
      EXPECT_NEAR(o->lambda[c], lambda[c], 1e-5 * scale) << "form " << form << ", lambda " << c;
    EXPECT_NEAR(o->kinetic_energy, f3r_kinetic_energy(m.get(), o->q, o->v), 1e-14);
    EXPECT_NEAR(o->potential_energy, f3r_potential_energy(m.get(), o->q), 1e-14);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(o->tip_deflection[i], f3r_model_tip_deflection(m.get(), o->q, i), 1e-15);
      EXPECT_NEAR(o->tip_deflection_rate[i], f3r_model_tip_deflection(m.get(), o->v, i), 1e-13);
    }
    double g[F3R_NCON], gv[F3R_NCON], worst = 0.0, worst_v = 0.0;
    f3r_constraints(m.get(), o->q, g);
    f3r_constraint_times(m.get(), o->q, o->v, gv);
    for (int c = 0; c < F3R_NCON; ++c)
      worst = std::max(worst, std::fabs(g[c])), worst_v = std::max(worst_v, std::fabs(gv[c]));
    EXPECT_DOUBLE_EQ(o->constraint_residual, worst);
    EXPECT_DOUBLE_EQ(o->velocity_residual, worst_v);
    EXPECT_NEAR(o->actuation_condition, f3r_model_actuation_condition(m.get(), o->q),
                1e-9 * o->actuation_condition);
  }
}

// The scripted inputs of test/scenes/all_effects.yaml plus a table on theta_2, written out
// here from the scene's numbers (not through f3r_input_value).
double AllEffectsInput(int index, double t) {
  switch (index) {
    case F3R_FORCE_RHO + 0: return t <= 0.002 ? 0.0 : 5.0;                       // step
    case F3R_FORCE_RHO + 1: return 1.0 + 2.0 * std::cos(2.0 * M_PI * 30.0 * t);  // harmonic
    case F3R_FORCE_THETA + 1: {  // table (0, 0), (0.01, 0.1), (0.02, -0.05), linear
      if (t <= 0.01) return 0.1 * t / 0.01;
      if (t <= 0.02) return 0.1 - 0.15 * (t - 0.01) / 0.01;
      return -0.05;
    }
    case F3R_FORCE_THETA + 2: {  // chirp 10 -> 100 Hz over 0.1 s, amplitude 0.2
      if (t > 0.1) return 0.0;
      return 0.2 * std::sin(2.0 * M_PI * (10.0 * t + 0.5 * 90.0 * t * t / 0.1));
    }
    default: return 0.0;
  }
}

// The passive forces on the leg joints written out from effects.c's formulas: viscous joint
// friction and in-plane gravity on the cylinder and the beam.
void PassiveForces(const f3r_model* m, const f3r_scene& s, const double* q, const double* v,
                   double passive[6]) {
  const double gx = s.gravity[0], gy = s.gravity[1];
  for (int i = 0; i < 3; ++i) {
    const double th = q[F3R_Q_THETA + i], e_x = std::cos(th), e_y = std::sin(th);
    const double g_e = gx * e_x + gy * e_y, g_n = -gx * e_y + gy * e_x;
    double mean = 0.0;  // int_0^1 w dxi
    for (int j = 0; j < m->link[i].modes; ++j)
      mean += m->link[i].mean[j] * q[m->link[i].eta_index + j];
    passive[i] = -s.friction_prismatic[i] * v[i] + m->link_mass * g_e;
    passive[3 + i] = -s.friction_revolute[i] * v[3 + i] +
                     (m->cylinder_mass * m->cylinder_length / 2.0 +
                      m->link_mass * (q[i] + m->link_length / 2.0)) *
                         g_n -
                     m->link_mass * mean * g_e;
  }
}

// The efforts of the six actuators are the held forces plus the scene's inputs (or, for the legs
// under actuator lag, the lag states, which follow a step as 1 - exp(-t/tau)); the passive forces
// are the rest of Q on the leg joints: friction and gravity.
TEST(Simulation, ActuatorEffortsAreHeldPlusScriptedAndPassiveIsTheRest) {
  for (int lagged = 0; lagged < 2; ++lagged) {
    f3r_scene s = f3r_default_scene();
    SceneTables owned{&s};
    f3r_error err{};
    ASSERT_EQ(
        f3r_scene_load((std::string(F3R_SOURCE_DIR) + "/test/scenes/all_effects.yaml").c_str(), &s,
                       &err),
        F3R_OK)
        << err.message;
    f3r_input& table = s.inputs[F3R_FORCE_THETA + 1];
    const double times[3] = {0.0, 0.01, 0.02}, values[3] = {0.0, 0.1, -0.05};
    ASSERT_EQ(f3r_input_set_table(&table, times, values, 3, table.table_hold, &err), F3R_OK);
    if (!lagged) s.actuator_lag = 0.0;
    auto m = MakeModel(s);
    ASSERT_EQ(m->n_lag, lagged ? 3 : 0);
    f3r_solver_settings set = f3r_solver_settings_from_scene(&s);
    set.rtol = 1e-10;
    set.atol = 1e-12;
    f3r_sim* raw = nullptr;
    ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    std::vector<double> held(m->nq, 0.0);
    held[F3R_FORCE_RHO + 2] = 1.5;
    held[F3R_FORCE_THETA + 0] = -0.02;
    held[F3R_FORCE_THETA + 1] = 0.01;
    ASSERT_EQ(f3r_sim_set_forces(sim.get(), held.data(), &err), F3R_OK) << err.message;
    const double tau = s.actuator_lag;
    for (double t : {0.0015, 0.004, 0.0137, 0.025, 0.04}) {
      ASSERT_EQ(f3r_sim_advance(sim.get(), t, &err), F3R_OK) << err.message;
      const f3r_outputs* o = f3r_sim_outputs(sim.get());
      double passive[6];
      PassiveForces(m.get(), s, o->q, o->v, passive);
      for (int j = 0; j < 6; ++j) {
        const double scripted = held[j] + AllEffectsInput(j, t);
        if (j >= F3R_FORCE_THETA || !lagged) {
          EXPECT_NEAR(o->actuator[j], scripted, 1e-14 * (1.0 + std::fabs(scripted)))
              << "joint " << j << " at " << t;
        } else if (j == F3R_FORCE_RHO) {  // the lag's step response, from rest
          const double delivered = t <= 0.002 ? 0.0 : 5.0 * (1.0 - std::exp(-(t - 0.002) / tau));
          EXPECT_NEAR(o->actuator[j], delivered, 1e-6) << "at " << t;
        }
        if (lagged && j < F3R_FORCE_THETA) {
          const double* y = f3r_sim_state(sim.get());
          EXPECT_EQ(o->actuator[j], y[f3r_lag_index(m.get(), set.formulation) + j]) << j;
        }
        EXPECT_NEAR(o->actuator[j] + o->passive[j], o->forces[j],
                    1e-13 * (1.0 + std::fabs(o->forces[j])))
            << "joint " << j << " at " << t;
        EXPECT_NEAR(o->passive[j], passive[j], 1e-12 * (1.0 + std::fabs(passive[j])))
            << "joint " << j << " at " << t;
      }
    }
  }
}

TEST(Simulation, NonFiniteForcesAreRejectedAndChangeNothing) {
  f3r_scene s = Scene("paper_sim1.yaml");
  auto m = MakeModel(s);
  f3r_sim* raw = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_sim_create(m.get(), nullptr, &raw, &err), F3R_OK);
  SimPtr sim(raw);
  std::vector<double> held(m->nq, 0.0);
  held[2] = NAN;
  EXPECT_EQ(f3r_sim_set_forces(sim.get(), held.data(), &err), F3R_ERR_ARGUMENT);
  EXPECT_NE(std::string(err.message).find("force[2]"), std::string::npos) << err.message;
  ASSERT_EQ(f3r_sim_advance(sim.get(), 0.01, &err), F3R_OK);
  EXPECT_EQ(f3r_sim_outputs(sim.get())->forces[2], 0.0);
}

// 1 when an explicit table's last stage is its step's solution (first same as last), from the
// coefficients as ARKODE or erk_tables.def has them.
int LastStageIsTheSolution(const char* name) {
  const f3r_erk_table* own = f3r_erk_table_find(name);
  ARKodeButcherTable arkode = own ? nullptr : ARKodeButcherTable_LoadERKByName(name);
  EXPECT_TRUE(own || arkode) << name;
  if (!own && !arkode) return 0;
  const int s = own ? own->stages : arkode->stages;
  auto a = [&](int i, int j) { return own ? own->A[i * s + j] : arkode->A[i][j]; };
  auto b = [&](int j) { return own ? own->b[j] : arkode->b[j]; };
  int fsal = (own ? own->c[s - 1] : arkode->c[s - 1]) == 1.0;
  for (int j = 0; j < s; ++j) fsal = fsal && a(s - 1, j) == b(j);
  ARKodeButcherTable_Free(arkode);
  return fsal;
}

// Every integrator and Butcher table follows the same end-effector path as IDA at a tight
// tolerance; an explicit table evaluates the right-hand side only for its stages (outputs every
// 0.1 ms add none: cubic Hermite output, y' only when outputs ask for it).
TEST(Simulation, EveryIntegratorAndTableFollowsTheSamePath) {
  f3r_scene scene = Scene("paper_sim3_fixed_free.yaml");
  scene.duration = 0.03;
  auto m = MakeModel(scene);
  auto run = [&](f3r_integrator integrator, const char* table, double rtol, f3r_sim_stats* stats) {
    f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
    set.integrator = integrator;
    std::snprintf(set.rk_table, sizeof set.rk_table, "%s", table ? table : "");
    set.rtol = rtol;
    set.atol = rtol * 1e-2;
    return PlatformPath(m.get(), set, 300, 1e-4, stats);
  };
  f3r_sim_stats ref_stats{};
  const std::vector<double> ref = run(F3R_INTEGRATOR_IDA, nullptr, 1e-11, &ref_stats);
  struct Case {
    f3r_integrator integrator;
    const char* table;
    int stages;
    double rtol, tolerance;  // m
  };
  std::vector<Case> cases = {{F3R_INTEGRATOR_ERK, nullptr, 13, 1e-8, 1e-9},
                             {F3R_INTEGRATOR_DIRK, nullptr, 7, 1e-7, 1e-7}};
  // every table a scene may name (f3r_rk_tables), with its stage count
  const std::map<std::string, int> stages = {{"ARKODE_FEHLBERG_13_7_8", 13},
                                             {"ARKODE_DORMAND_PRINCE_7_4_5", 7},
                                             {"ARKODE_VERNER_8_5_6", 8},
                                             {"dormand_prince_8_5", 12},
                                             {"verner_8_7", 13},
                                             {"verner_9_8", 16},
                                             {"ARKODE_KVAERNO_7_4_5", 7},
                                             {"ARKODE_ARK548L2SA_DIRK_8_4_5", 8},
                                             {"ARKODE_SDIRK_5_3_4", 5}};
  for (f3r_integrator integrator : {F3R_INTEGRATOR_ERK, F3R_INTEGRATOR_DIRK})
    for (const char* const* t = f3r_rk_tables(integrator); *t; ++t) {
      ASSERT_TRUE(stages.count(*t)) << *t;
      const bool erk = integrator == F3R_INTEGRATOR_ERK;
      const bool sixth =
          !strcmp(*t, "ARKODE_VERNER_8_5_6") || !strcmp(*t, "ARKODE_DORMAND_PRINCE_7_4_5");
      cases.push_back({integrator, *t, stages.at(*t), erk ? (sixth ? 1e-9 : 1e-8) : 1e-7,
                       erk ? (sixth ? 1e-8 : 1e-9) : 1e-7});
    }
  EXPECT_EQ(cases.size(), 2 + stages.size());
  for (const Case& c : cases) {
    f3r_sim_stats stats{};
    const std::vector<double> path = run(c.integrator, c.table, c.rtol, &stats);
    double worst = 0.0;
    for (size_t k = 0; k < ref.size(); ++k) worst = std::max(worst, std::fabs(path[k] - ref[k]));
    EXPECT_LT(worst, c.tolerance) << (c.table ? c.table : "default") << " integrator "
                                  << c.integrator;
    EXPECT_GT(stats.steps, 100);
    if (c.integrator ==
        F3R_INTEGRATOR_ERK) {  // a step rejected by the error test costs its stages too
      // ... and each of the 300 outputs costs y' (one) and the quartic interpolant's inner point
      // at ARKODE's two interpolations (stepper.c)
      EXPECT_LE(stats.residual_evals,
                (long)c.stages * (stats.steps + stats.error_test_failures + 1) + 3 * 300)
          << (c.table ? c.table : "default");
      // ... and no fewer than its stages: only a table whose last stage is the step's solution
      // (c = 1, its row of A = b) may start the next step from it, and a retried step reuses
      // only the first. SUNDIALS 6.4.1 reused the last stage of every table with c = 1, and ran
      // Fehlberg 7(8) on 12 right-hand sides a step (stepper.c).
      const int fsal = LastStageIsTheSolution(c.table ? c.table : "ARKODE_FEHLBERG_13_7_8");
      EXPECT_GE(stats.residual_evals,
                (long)(c.stages - fsal) * stats.steps + (c.stages - 1L) * stats.error_test_failures)
          << (c.table ? c.table : "default");
    }
  }
}

// Outputs between steps keep the digits the steps have (issue 28, item 5): on rigid links ERK's
// steps are longer than the 1 ms outputs, so the outputs are interpolated. Against the same run
// stopping at every output (every output a step end, rtol 1e-12), at rtol 1e-9 and atol 1e-11.
// Fehlberg 7(8), once it evaluated all its stages (#59), stepped up to 46 ms and its quartic
// Hermite output erred by 5.3e-7 m; no step spans more than four outputs now (stepper.c):
// 5.3e-11 m (docs/solvers.md, "Outputs between steps").
TEST(Simulation, ExplicitOutputsBetweenStepsKeepTheStepsDigits) {
  const f3r_scene scene = Scene("rigid.yaml");
  auto m = MakeModel(scene);
  auto run = [&](double rtol, int stop_at_outputs, f3r_sim_stats* stats) {
    f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
    set.integrator = F3R_INTEGRATOR_ERK;
    set.rtol = rtol;
    set.atol = rtol * 1e-2;
    set.stop_at_outputs = stop_at_outputs;
    return PlatformPath(m.get(), set, 250, 1e-3, stats);
  };
  f3r_sim_stats ref_stats{}, stats{};
  const std::vector<double> ref = run(1e-12, 1, &ref_stats);
  const std::vector<double> path = run(1e-9, 0, &stats);
  EXPECT_LT(stats.steps, 100);  // interpolated: far fewer steps than the 250 outputs
  EXPECT_LE(stats.last_step, 4e-3 * (1.0 + 1e-12));
  double worst = 0.0;
  for (size_t k = 0; k < ref.size(); k += 2)
    worst = std::max(worst, std::hypot(path[k] - ref[k], path[k + 1] - ref[k + 1]));
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(worst, 1e-12);  // the outputs are interpolated, not step ends
}

// Steps ARKODE has completed, as its step hook counts them (beside the counters it reports).
long steps_hooked = 0;
int CountStep(realtype, N_Vector, void*) {
  ++steps_hooked;
  return 0;
}

// The statistics count each step and evaluation once however often the run restarts (issue 47,
// item 6). ARKODE's Reset keeps counting, and each restart added its whole count so far again
// (rest.yaml with a 100-point hold table on rho_1: ERK reported 545,735 steps for 11,112); IDA
// zeroes its linear solver's counters only in the next IDASolve, so the Jacobians counted twice
// in between. Over held forces changed every 5 ms, and again after a reset: against the
// stepper's own count of residual (right-hand side) calls, ARKODE's step hook (with which it
// evaluates f afresh at each step's end, as both counts see) and, for DIRK, the right-hand sides
// of its Jacobian; a restart itself counts nothing but the restart.
TEST(Simulation, StatisticsCountTheWorkOnceAcrossRestarts) {
  const f3r_scene scene = Scene("rest.yaml");
  auto m = MakeModel(scene);
  for (f3r_integrator integrator : {F3R_INTEGRATOR_IDA, F3R_INTEGRATOR_ERK, F3R_INTEGRATOR_DIRK}) {
    SCOPED_TRACE(::testing::Message() << "integrator " << integrator);
    f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
    set.integrator = integrator;
    f3r_sim* raw = nullptr;
    f3r_error err{};
    ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    const f3r_stepper* st = f3r_sim_stepper(sim.get());
    steps_hooked = 0;
    if (integrator == F3R_INTEGRATOR_ERK) {
      ASSERT_EQ(ERKStepSetPostprocessStepFn(st->mem, CountStep), ARK_SUCCESS);
    } else if (integrator == F3R_INTEGRATOR_DIRK) {
      ASSERT_EQ(ARKStepSetPostprocessStepFn(st->mem, CountStep), ARK_SUCCESS);
    }
    const long ny = f3r_state_size(m.get(), set.formulation);
    long calls_before = 0, steps_before = 0, jacobian_calls_before = 0;  // those of the last run
    for (int run = 0; run < 2; ++run) {
      std::vector<double> held(m->nq, 0.0);
      for (int k = 0; k < 20; ++k) {
        held[F3R_FORCE_RHO] = 5.0 + k % 2;
        const f3r_sim_stats before = f3r_sim_outputs(sim.get())->stats;
        ASSERT_EQ(f3r_sim_set_forces(sim.get(), held.data(), &err), F3R_OK) << err.message;
        const f3r_sim_stats after = f3r_sim_outputs(sim.get())->stats;
        EXPECT_EQ(after.restarts, before.restarts + 1);
        EXPECT_EQ(after.steps, before.steps);
        EXPECT_EQ(after.residual_evals, before.residual_evals);
        EXPECT_EQ(after.jacobian_evals, before.jacobian_evals);
        EXPECT_EQ(after.error_test_failures, before.error_test_failures);
        EXPECT_EQ(after.nonlinear_failures, before.nonlinear_failures);
        ASSERT_EQ(f3r_sim_advance(sim.get(), (k + 1) * 5e-3, &err), F3R_OK) << err.message;
      }
      const f3r_sim_stats stats = f3r_sim_outputs(sim.get())->stats;
      EXPECT_EQ(stats.restarts, 20);
      EXPECT_EQ(stats.recoverable_errors, 0);
      EXPECT_GT(stats.steps, 100);
      EXPECT_EQ(stats.residual_evals, st->residual_calls - calls_before);
      if (integrator != F3R_INTEGRATOR_IDA) {
        EXPECT_EQ(stats.steps, steps_hooked - steps_before);
      }
      if (integrator == F3R_INTEGRATOR_DIRK) {
        EXPECT_GT(stats.jacobian_evals, 0);
        EXPECT_EQ(stats.jacobian_evals * ny, st->jacobian_rhs_evals - jacobian_calls_before);
      }
      calls_before = st->residual_calls;
      steps_before = steps_hooked;
      jacobian_calls_before = st->jacobian_rhs_evals;
      ASSERT_EQ(f3r_sim_reset(sim.get(), &err), F3R_OK) << err.message;
      const f3r_sim_stats anew = f3r_sim_outputs(sim.get())->stats;
      EXPECT_EQ(anew.steps, 0);
      EXPECT_EQ(anew.residual_evals, 0);
      EXPECT_EQ(anew.jacobian_evals, 0);
      EXPECT_EQ(anew.error_test_failures, 0);
      EXPECT_EQ(anew.nonlinear_failures, 0);
      EXPECT_EQ(anew.restarts, 0);
    }
  }
}

TEST(Simulation, UnknownButcherTableIsAnErrorNamingIt) {
  f3r_scene s = Scene("paper_sim1.yaml");
  auto m = MakeModel(s);
  f3r_solver_settings settings = f3r_solver_settings_from_scene(&s);
  settings.integrator = F3R_INTEGRATOR_ERK;
  std::snprintf(settings.rk_table, sizeof settings.rk_table, "NO_SUCH_TABLE");
  f3r_sim* raw = nullptr;
  f3r_error err{};
  EXPECT_NE(f3r_sim_create(m.get(), &settings, &raw, &err), F3R_OK);
  EXPECT_EQ(raw, nullptr);
  EXPECT_NE(std::string(err.message).find("NO_SUCH_TABLE"), std::string::npos) << err.message;
}

TEST(Simulation, RefusesTheIndexThreeFormWhichIsForExternalSolvers) {
  f3r_scene s = Scene("paper_sim1.yaml");
  auto m = MakeModel(s);
  f3r_solver_settings settings = f3r_solver_settings_from_scene(&s);
  settings.formulation = F3R_FORMULATION_INDEX3;
  f3r_sim* raw = nullptr;
  f3r_error err{};
  EXPECT_EQ(f3r_sim_create(m.get(), &settings, &raw, &err), F3R_ERR_ARGUMENT);
  EXPECT_EQ(raw, nullptr);
  EXPECT_NE(std::string(err.message).find("index3"), std::string::npos) << err.message;
}

}  // namespace

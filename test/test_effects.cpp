// The scene's effects: each against an independent computation, each toggled alone changes
// exactly the residual rows it should, and energy stays balanced with all of them on.
#include <gtest/gtest.h>

#include <set>

#include "queries.h"
#include "independent_lagrangian.h"
#include "test_support.h"

namespace {

// Runs a scene for `steps` ms; the largest energy-balance error, the energy scale it is measured
// against (T + V or the work done, whichever is larger) and the work done at the end.
void EnergyBalanceOverRun(const f3r_scene& s, int steps, double* worst, double* scale,
                          double* final_work = nullptr) {
  auto m = MakeModel(s);
  f3r_sim* raw = nullptr;
  f3r_error err{};
  ASSERT_EQ(f3r_sim_create(m.get(), nullptr, &raw, &err), F3R_OK) << err.message;
  SimPtr sim(raw);
  for (int k = 1; k <= steps; ++k) {
    ASSERT_EQ(f3r_sim_advance(sim.get(), k * 1e-3, &err), F3R_OK) << err.message;
    const f3r_outputs* o = f3r_sim_outputs(sim.get());
    *worst = std::max(*worst, o->energy_balance_error);
    *scale =
        std::max({*scale, o->kinetic_energy + o->potential_energy, std::fabs(o->external_work)});
    if (final_work) *final_work = o->external_work;
  }
}

f3r_scene Flexible() {
  f3r_scene s =
      SceneWithLinks(F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_PINNED, 2, F3R_LINK_FIXED_FREE, 1);
  s.formulation = F3R_FORMULATION_DAE;
  return s;
}

TEST(Effects, GravityIsMinusTheGradientOfAnIndependentPotential) {
  f3r_scene s = Flexible();
  const double tilt = 0.3;
  s.gravity[0] = 2.0;
  s.gravity[1] = -9.81 * std::sin(tilt);
  s.gravity[2] = -9.81 * std::cos(tilt);
  s.payload_mass = 0.1;
  auto m = MakeModel(s);
  std::mt19937 rng(5);
  RandomState st = MakeRandomState(m.get(), rng);
  std::vector<double> Q(F3R_MAX_Q), zero(F3R_MAX_Q, 0.0);
  f3r_generalized_forces(m.get(), 0.0, nullptr, st.q.data(), zero.data(), Q.data());
  for (int j = 0; j < m->nq; ++j) {
    std::vector<double> qp(st.q), qm(st.q);
    const double h = 1e-6;
    qp[j] += h;
    qm[j] -= h;
    const double dV = (indep_gravity_potential(m.get(), qp.data()) -
                       indep_gravity_potential(m.get(), qm.data())) /
                      (2 * h);
    EXPECT_NEAR(Q[j], -dV, 1e-7 * (1.0 + std::fabs(dV))) << "coordinate " << j;
  }
}

TEST(Effects, DerivativesOfAllEffectsMatchFiniteDifferences) {
  f3r_scene s = Flexible();
  s.gravity[0] = 1.0;
  s.gravity[1] = -3.0;
  for (int i = 0; i < 3; ++i) {
    s.friction_prismatic[i] = 0.5 + i;
    s.friction_revolute[i] = 0.01 * (i + 1);
    s.links[i].damping_ratio = 0.02;
  }
  auto m = MakeModel(s);
  const int nq = m->nq;
  std::mt19937 rng(9);
  RandomState st = MakeRandomState(m.get(), rng);
  std::vector<double> dq((size_t)nq * nq, 0.0), dv((size_t)nq * nq, 0.0), Qp(F3R_MAX_Q),
      Qm(F3R_MAX_Q);
  f3r_add_generalized_forces_dq(m.get(), st.q.data(), st.v.data(), 1.0, dq.data(), nq);
  f3r_add_generalized_forces_dv(m.get(), st.q.data(), st.v.data(), 1.0, dv.data(), nq);
  for (int j = 0; j < nq; ++j) {
    for (int which = 0; which < 2; ++which) {
      std::vector<double> xp = which ? st.v : st.q, xm = xp;
      const double h = 1e-6;
      xp[j] += h;
      xm[j] -= h;
      f3r_generalized_forces(m.get(), 0.1, nullptr, which ? st.q.data() : xp.data(),
                             which ? xp.data() : st.v.data(), Qp.data());
      f3r_generalized_forces(m.get(), 0.1, nullptr, which ? st.q.data() : xm.data(),
                             which ? xm.data() : st.v.data(), Qm.data());
      const auto& A = which ? dv : dq;
      for (int i = 0; i < nq; ++i)
        EXPECT_NEAR(A[(size_t)j * nq + i], (Qp[i] - Qm[i]) / (2 * h),
                    1e-6 * (1 + std::fabs(A[(size_t)j * nq + i])))
            << (which ? "dQ/dv" : "dQ/dq") << " row " << i << " column " << j;
    }
  }
}

// Rows of the dae residual that differ between two models at the same state.
std::set<int> ChangedRows(const f3r_scene& a, const f3r_scene& b) {
  auto ma = MakeModel(a), mb = MakeModel(b);
  const int ny = f3r_state_size(ma.get(), F3R_FORMULATION_DAE);
  std::mt19937 rng(21);
  RandomState st = MakeRandomState(ma.get(), rng);
  std::vector<double> y(ny), yp(ny), ra(ny), rb(ny);
  const int nq = ma->nq;
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < nq; ++k) {
    y[k] = st.q[k];
    y[nq + k] = st.v[k];
    yp[k] = st.v[k];
    yp[nq + k] = st.a[k];
  }
  for (int k = 2 * nq; k < ny; ++k) y[k] = u(rng);
  WorkspacePtr wa(f3r_workspace_create(ma.get())), wb(f3r_workspace_create(mb.get()));
  f3r_residual(ma.get(), F3R_FORMULATION_DAE, 0.01, y.data(), yp.data(), nullptr, ra.data(),
               wa.get());
  f3r_residual(mb.get(), F3R_FORMULATION_DAE, 0.01, y.data(), yp.data(), nullptr, rb.data(),
               wb.get());
  std::set<int> rows;
  for (int k = 0; k < ny; ++k)
    if (ra[k] != rb[k]) rows.insert(k);
  return rows;
}

TEST(Effects, EachEffectAloneChangesExactlyItsTerms) {
  const f3r_scene base = Flexible();
  auto m = MakeModel(base);
  const int nq = m->nq, dyn = nq, w_row = 2 * nq + 12;
  auto rows = [&](std::initializer_list<int> coords, bool work) {
    std::set<int> r;
    for (int c : coords) r.insert(dyn + c);
    if (work) r.insert(w_row);
    return r;
  };
  std::vector<int> etas;
  for (int k = 9; k < nq; ++k) etas.push_back(k);

  f3r_scene s = base;
  s.gravity[0] = 3.0;
  std::set<int> expect = rows({0, 1, 2, 3, 4, 5, 6}, true);
  for (int k : etas) expect.insert(dyn + k);
  EXPECT_EQ(ChangedRows(base, s), expect) << "gravity along X";

  s = base;
  s.friction_prismatic[1] = 2.0;
  s.friction_revolute[2] = 0.1;
  EXPECT_EQ(ChangedRows(base, s), rows({1, 5}, true)) << "joint friction on rho_2 and theta_3";

  s = base;
  s.links[0].damping_ratio = 0.05;
  EXPECT_EQ(ChangedRows(base, s), rows({9, 10, 11}, true)) << "damping of link 1's modes";

  s = base;
  s.payload_mass = 0.5;
  s.payload_inertia = 1e-3;
  EXPECT_EQ(ChangedRows(base, s), rows({6, 7, 8}, false)) << "payload on the platform";

  s = base;
  s.exact_kinematics = 1;
  expect = rows({0, 1, 2, 3, 4, 5}, false);
  for (int k : etas) expect.insert(dyn + k);
  EXPECT_EQ(ChangedRows(base, s), expect) << "exact kinematics";

  // Gravity along Z only does no work in the plane: the effect is not even compiled in.
  s = base;
  s.gravity[2] = -20.0;
  EXPECT_TRUE(ChangedRows(base, s).empty());
  EXPECT_EQ(MakeModel(s)->n_effects, 0);
}

TEST(Effects, EverythingOffIsTheRigidModel) {
  f3r_scene s = f3r_default_scene();
  auto m = MakeModel(s);
  EXPECT_EQ(m->nq, 9);
  EXPECT_EQ(m->n_effects, 0);
  EXPECT_EQ(f3r_state_size(m.get(), F3R_FORMULATION_MINIMAL), 7);
}

TEST(Effects, EnergyBalancesWithGravityFrictionDampingAndPayload) {
  for (auto form : {F3R_FORMULATION_DAE, F3R_FORMULATION_MINIMAL}) {
    f3r_scene s =
        SceneWithLinks(F3R_LINK_FIXED_FREE, 2, F3R_LINK_FIXED_FREE, 2, F3R_LINK_FIXED_FREE, 2);
    s.formulation = form;
    s.gravity[1] = -9.81 * std::sin(0.2);
    s.gravity[2] = -9.81 * std::cos(0.2);
    s.payload_mass = 0.05;
    for (int i = 0; i < 3; ++i) {
      s.friction_prismatic[i] = 0.3;
      s.friction_revolute[i] = 0.002;
      s.links[i].damping_ratio = 0.01;
    }
    s.links[0].eta0[0] = 5e-4;
    s.inputs[F3R_FORCE_RHO].kind = F3R_INPUT_HARMONIC;
    s.inputs[F3R_FORCE_RHO].amplitude = 2.0;
    s.inputs[F3R_FORCE_RHO].omega = 2 * M_PI * 30;
    s.rtol = 1e-11;
    s.atol = 1e-13;
    double worst = 0.0, scale = 0.0, work = 0.0;
    ASSERT_NO_FATAL_FAILURE(EnergyBalanceOverRun(s, 100, &worst, &scale, &work));
    EXPECT_LT(worst, 1e-8 * scale) << "formulation " << form << ": T + V - W drifts";
    std::printf("formulation %d: energy balance %.3e of %.3e J\n", (int)form, worst, scale);
    EXPECT_LT(work, 0.5 * scale) << "friction and damping dissipate";
  }
}

TEST(Effects, ScriptedInputShapesAndTheirBreakpoints) {
  f3r_input step{};
  step.kind = F3R_INPUT_STEP;
  step.t0 = 0.01;
  step.before = 1.0;
  step.after = 3.0;
  EXPECT_EQ(f3r_input_value(&step, 0.01), 1.0);
  EXPECT_EQ(f3r_input_value(&step, 0.0100001), 3.0);
  f3r_input ramp{};
  ramp.kind = F3R_INPUT_RAMP;
  ramp.t0 = 1.0;
  ramp.t1 = 3.0;
  ramp.before = 0.0;
  ramp.after = 4.0;
  EXPECT_DOUBLE_EQ(f3r_input_value(&ramp, 2.5), 3.0);
  f3r_input chirp{};
  chirp.kind = F3R_INPUT_CHIRP;
  chirp.amplitude = 2.0;
  chirp.f0 = 10.0;
  chirp.f1 = 30.0;
  chirp.t0 = 0.0;
  chirp.t1 = 1.0;
  // phase 2 pi (f0 t + (f1 - f0) t^2 / 2): at t = 0.5, 2 pi * 7.5
  EXPECT_NEAR(f3r_input_value(&chirp, 0.5), 2.0 * std::sin(2 * M_PI * 7.5), 1e-12);
  EXPECT_EQ(f3r_input_max_frequency(&chirp), 30.0);
  f3r_input table{};
  table.kind = F3R_INPUT_TABLE;
  table.table_size = 3;
  double time[3] = {0.0, 0.1, 0.3}, value[3] = {0.0, 5.0, 1.0};
  table.table_time = time; /* a view of these lists: nothing to free */
  table.table_value = value;
  EXPECT_DOUBLE_EQ(f3r_input_value(&table, 0.2), 3.0);
  EXPECT_DOUBLE_EQ(f3r_input_value(&table, 1.0), 1.0);
  double times[8];
  EXPECT_EQ(f3r_input_breakpoints(&table, times, 8), 3);
}

// A full table, uneven knots, both interpolations: every value at, between, before and after the
// knots equals the definition, evaluated here by scanning the knots from the start.
// Harmonic inputs with the same frequency and phase share one cosine per evaluation; each still
// gets its own offset and amplitude, and a different phase or frequency gets its own cosine.
TEST(Effects, HarmonicInputsSharingAWaveKeepTheirOwnValues) {
  f3r_scene s = Flexible();
  auto harmonic = [&](int n, double offset, double amplitude, double frequency, double phase) {
    s.inputs[n].kind = F3R_INPUT_HARMONIC;
    s.inputs[n].offset = offset;
    s.inputs[n].amplitude = amplitude;
    s.inputs[n].omega = 2 * M_PI * frequency;
    s.inputs[n].phase = phase;
  };
  harmonic(F3R_FORCE_RHO + 0, -50.0, 50.0, 20.0, 0.0);
  harmonic(F3R_FORCE_RHO + 1, 1.0, 7.0, 20.0, 0.0);         // rho_1's wave
  harmonic(F3R_FORCE_THETA + 0, 0.0, 5.0, 20.0, 0.3);       // another phase
  harmonic(F3R_FORCE_THETA + 1, 0.0, 5.0, 200.0, 0.0);      // another frequency
  harmonic(F3R_FORCE_PLATFORM + 0, 0.0, 100.0, 20.0, 0.0);  // rho_1's wave again
  harmonic(F3R_FORCE_PLATFORM + 2, 0.0, 2.0, 200.0, 0.0);   // theta_2's
  s.inputs[F3R_FORCE_THETA + 2].kind = F3R_INPUT_STEP;
  s.inputs[F3R_FORCE_THETA + 2].before = 1.0;
  s.inputs[F3R_FORCE_THETA + 2].after = 2.0;
  auto m = MakeModel(s);
  const int expected_source[F3R_RIGID_FORCES] = {0, 0, -1, 3, 4, -1, 0, -1, 4};
  for (int n = 0; n < F3R_RIGID_FORCES; ++n) EXPECT_EQ(m->wave_source[n], expected_source[n]) << n;
  double q[F3R_MAX_Q] = {0}, v[F3R_MAX_Q] = {0};
  for (double t : {0.0, 1.3e-3, 0.0123, 0.25}) {
    f3r_data d{};
    d.t = t;
    d.q = q;
    d.v = v;
    double Q[F3R_MAX_Q] = {0};
    f3r_effects_add_forces(m.get(), &d, Q);
    for (int n = 0; n < F3R_RIGID_FORCES; ++n)
      EXPECT_EQ(Q[n], 0.0 + f3r_input_value(&s.inputs[n], t)) << "input " << n << " at t " << t;
  }
}

TEST(Effects, LongTablesGiveTheValueOfTheirInterval) {
  f3r_input table{};
  table.kind = F3R_INPUT_TABLE;
  table.table_size = F3R_MAX_TABLE;
  std::vector<double> time(F3R_MAX_TABLE), value(F3R_MAX_TABLE);
  table.table_time = time.data();
  table.table_value = value.data();
  double t = 0.0;
  for (int k = 0; k < F3R_MAX_TABLE; ++k) {
    t += 1e-3 * (1.0 + (k * 7919 % 13));  // uneven steps
    table.table_time[k] = t;
    table.table_value[k] = std::sin(0.37 * k) * 10.0;
  }
  auto reference = [&](double at) {
    const int n = table.table_size;
    if (at <= table.table_time[0]) return table.table_value[0];
    if (at >= table.table_time[n - 1]) return table.table_value[n - 1];
    int k = 1;
    while (table.table_time[k] < at) ++k;
    if (table.table_hold) return table.table_value[k - 1];
    const double w =
        (at - table.table_time[k - 1]) / (table.table_time[k] - table.table_time[k - 1]);
    return table.table_value[k - 1] + w * (table.table_value[k] - table.table_value[k - 1]);
  };
  for (int hold = 0; hold < 2; ++hold) {
    table.table_hold = hold;
    std::vector<double> probes = {-1.0, table.table_time[0], t, t + 1.0};
    for (int k = 0; k + 1 < F3R_MAX_TABLE; ++k) {
      const double a = table.table_time[k], b = table.table_time[k + 1];
      probes.insert(probes.end(), {a, std::nextafter(a, b), 0.5 * (a + b), std::nextafter(b, a)});
    }
    for (double at : probes)
      ASSERT_EQ(f3r_input_value(&table, at), reference(at)) << "t = " << at << ", hold " << hold;
  }
}

TEST(Effects, AStepInputEqualsHeldForcesAppliedAtTheSameTime) {
  f3r_scene scripted =
      SceneWithLinks(F3R_LINK_FIXED_FREE, 2, F3R_LINK_FIXED_FREE, 2, F3R_LINK_FIXED_FREE, 2);
  scripted.inputs[0].kind = F3R_INPUT_STEP;
  scripted.inputs[0].t0 = 0.005;
  scripted.inputs[0].before = 0.0;
  scripted.inputs[0].after = 5.0;
  f3r_scene held = scripted;
  held.inputs[0] = f3r_input{};
  auto ms = MakeModel(scripted), mh = MakeModel(held);
  f3r_error err{};
  f3r_sim *a = nullptr, *b = nullptr;
  ASSERT_EQ(f3r_sim_create(ms.get(), nullptr, &a, &err), F3R_OK);
  ASSERT_EQ(f3r_sim_create(mh.get(), nullptr, &b, &err), F3R_OK);
  SimPtr sa(a), sb(b);
  ASSERT_EQ(f3r_sim_advance(sa.get(), 0.02, &err), F3R_OK) << err.message;
  ASSERT_EQ(f3r_sim_advance(sb.get(), 0.005, &err), F3R_OK);
  std::vector<double> f(mh->nq, 0.0);
  f[0] = 5.0;
  ASSERT_EQ(f3r_sim_set_forces(sb.get(), f.data(), &err), F3R_OK);
  ASSERT_EQ(f3r_sim_advance(sb.get(), 0.02, &err), F3R_OK);
  const f3r_outputs* oa = f3r_sim_outputs(sa.get());
  const double xa = oa->q[6], ya = oa->q[7];
  const f3r_outputs* ob = f3r_sim_outputs(sb.get());
  EXPECT_NEAR(xa, ob->q[6], 1e-10);
  EXPECT_NEAR(ya, ob->q[7], 1e-10);
  EXPECT_GT(std::fabs(xa), 1e-6);
}

}  // namespace

namespace {

TEST(Effects, ActuatorLagFollowsTheFirstOrderResponse) {
  for (auto form : {F3R_FORMULATION_DAE, F3R_FORMULATION_MINIMAL}) {
    f3r_scene s =
        SceneWithLinks(F3R_LINK_FIXED_FREE, 1, F3R_LINK_FIXED_FREE, 1, F3R_LINK_FIXED_FREE, 1);
    s.formulation = form;
    s.actuator_lag = 0.004;
    s.inputs[0].kind = F3R_INPUT_STEP;
    s.inputs[0].t0 = 0.002;
    s.inputs[0].after = 5.0;
    s.rtol = 1e-10;
    s.atol = 1e-12;
    auto m = MakeModel(s);
    EXPECT_EQ(f3r_state_size(m.get(), form),
              form == F3R_FORMULATION_DAE ? 2 * 12 + 12 + 3 + 1 : 2 * 6 + 3 + 1);
    f3r_sim* raw = nullptr;
    f3r_error err{};
    ASSERT_EQ(f3r_sim_create(m.get(), nullptr, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    for (double t : {0.002, 0.006, 0.014}) {
      ASSERT_EQ(f3r_sim_advance(sim.get(), t, &err), F3R_OK) << err.message;
      const double expected = 5.0 * (1.0 - std::exp(-(t - 0.002) / 0.004));
      EXPECT_NEAR(f3r_sim_outputs(sim.get())->forces[0], expected, 1e-7) << "t = " << t;
    }
  }
}

TEST(Effects, AllEffectsTogetherKeepTheEnergyBalance) {
  for (auto form : {F3R_FORMULATION_DAE, F3R_FORMULATION_MINIMAL}) {
    f3r_scene s;
    f3r_error err{};
    ASSERT_EQ(
        f3r_scene_load((std::string(F3R_SOURCE_DIR) + "/test/scenes/all_effects.yaml").c_str(), &s,
                       &err),
        F3R_OK)
        << err.message;
    s.formulation = form;
    s.rtol = 1e-10;
    s.atol = 1e-12;
    double worst = 0.0, scale = 0.0;
    ASSERT_NO_FATAL_FAILURE(EnergyBalanceOverRun(s, 50, &worst, &scale));
    EXPECT_LT(worst, 1e-8 * scale) << "formulation " << form;
  }
}

}  // namespace

#include <Eigen/Dense>

namespace {

// 1 / (E^T M~^-1 E) for leg i: the effective mass of rho_i with the loops closed, from an
// independent dense solve of [M -G^T; G 0].
double EffectiveMass(const f3r_model* m, const double* q, int leg) {
  const int nq = m->nq, n = nq + F3R_NCON;
  std::vector<double> K((size_t)n * n, 0.0);
  f3r_add_mass_matrix(m, q, 1.0, K.data(), n);
  f3r_add_constraint_jacobian_transpose(m, q, -1.0, K.data() + (size_t)nq * n, n);
  f3r_add_constraint_jacobian(m, q, 1.0, K.data() + nq, n);
  Eigen::Map<Eigen::MatrixXd> A(K.data(), n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  b(leg) = 1.0;
  const Eigen::VectorXd x = A.fullPivLu().solve(b);
  return 1.0 / x(leg);
}

TEST(Effects, EndStopImpactsAreLocatedAndObeyTheRestitutionLaw) {
  f3r_scene s = f3r_default_scene();
  SceneTables owned{&s};
  f3r_error err{};
  ASSERT_EQ(f3r_scene_load(ScenePath("end_stop_impact.yaml").c_str(), &s, &err), F3R_OK)
      << err.message;
  s.rtol = 1e-10;
  s.atol = 1e-12;
  auto m = MakeModel(s);
  f3r_sim* raw = nullptr;
  ASSERT_EQ(f3r_sim_create(m.get(), nullptr, &raw, &err), F3R_OK) << err.message;
  SimPtr sim(raw);
  const double c = s.restitution;
  long seen = 0;
  double lowest = 1.0, highest = -1.0, worst_energy = 0.0, scale = 0.0;
  for (int k = 1; k <= 4000; ++k) {
    ASSERT_EQ(f3r_sim_advance(sim.get(), k * 1e-4, &err), F3R_OK) << err.message;
    const f3r_outputs* o = f3r_sim_outputs(sim.get());
    lowest = std::min(lowest, o->q[0]);
    highest = std::max(highest, o->q[0]);
    worst_energy = std::max(worst_energy, o->energy_balance_error);
    scale = std::max(scale, o->kinetic_energy + o->potential_energy);
    if (o->impacts == seen) continue;
    seen = o->impacts;
    const f3r_impact_record& r = o->last_impact;
    const double stop = r.at_max ? s.stroke_max : s.stroke_min;
    EXPECT_NEAR(r.rho, stop, 1e-9) << "impact at t = " << r.t << " is located on the stop";
    EXPECT_NEAR(r.rate_after, -c * r.rate_before, 1e-12 * std::fabs(r.rate_before));
    // Normal kinetic energy 1/2 m_eff rho'^2 falls to c^2 of itself; nothing else changes.
    // The record's state is the one just before the restart: recompute m_eff at the stop.
    std::vector<double> q(r.q, r.q + m->nq);
    const double normal_before =
        0.5 * EffectiveMass(m.get(), q.data(), 0) * r.rate_before * r.rate_before;
    EXPECT_NEAR(r.kinetic_before - r.kinetic_after, (1 - c * c) * normal_before,
                1e-3 * normal_before)
        << "t = " << r.t;
  }
  EXPECT_GE(seen, 3) << "the pulses drive piston 1 into its stops repeatedly";
  EXPECT_GE(lowest, s.stroke_min - 1e-9);
  EXPECT_LE(highest, s.stroke_max + 1e-9);
  EXPECT_LT(worst_energy, 1e-6 * scale) << "T + V - W + impact losses";
}

}  // namespace

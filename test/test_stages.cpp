// Every stage of the equations of motion against an independent computation: Lagrange's
// equations from quadrature energies, and finite differences of the constraint functions and of
// the stages themselves.
#include <gtest/gtest.h>

#include <functional>
#include <random>

#include "queries.h"
#include "independent_lagrangian.h"
#include "test_support.h"

namespace {

struct LinkCase {
  const char* name;
  f3r_link_model a, b, c;
  int ra, rb, rc;
  int corrected;  // links.static_correction on every flexible link
};

const LinkCase kCases[] = {
    {"rigid", F3R_LINK_RIGID, F3R_LINK_RIGID, F3R_LINK_RIGID, 0, 0, 0, 0},
    {"fixed_pinned_r3", F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_PINNED, 3, 3,
     3, 0},
    {"fixed_free_r3", F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, 3, 3, 3, 0},
    {"mixed", F3R_LINK_RIGID, F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_FREE, 0, 2, 5, 0},
    {"fixed_free_r8", F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, 8, 8, 8, 0},
    // the static shapes: the independent Lagrangian integrates their closed forms itself
    {"fixed_free_r1_corrected", F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, 1, 1,
     1, 1},
    {"mixed_corrected", F3R_LINK_RIGID, F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_FREE, 0, 2, 3, 1},
};

ModelPtr CaseModel(const LinkCase& c, bool exact) {
  f3r_scene s = SceneWithLinks(c.a, c.ra, c.b, c.rb, c.c, c.rc, exact);
  for (int i = 0; i < 3; ++i) s.links[i].static_correction = c.corrected && s.links[i].modes > 0;
  return MakeModel(s);
}

// Dense column-major matrix from an add-into function.
std::vector<double> Dense(int rows, int cols, const std::function<void(double*, int)>& add) {
  std::vector<double> A((size_t)rows * cols, 0.0);
  add(A.data(), rows);
  return A;
}

// Central-difference Jacobian of f: R^n -> R^rows at x.
std::vector<double> Numeric(int rows, const std::vector<double>& x, int n,
                            const std::function<void(const double*, double*)>& f, double step) {
  std::vector<double> J((size_t)rows * n), fp(rows), fm(rows), xp(x), xm(x);
  for (int j = 0; j < n; ++j) {
    const double h = step * std::max(1.0, std::fabs(x[j]));
    xp = x;
    xm = x;
    xp[j] += h;
    xm[j] -= h;
    f(xp.data(), fp.data());
    f(xm.data(), fm.data());
    for (int i = 0; i < rows; ++i) J[(size_t)j * rows + i] = (fp[i] - fm[i]) / (2 * h);
  }
  return J;
}

void ExpectMatrixNear(const std::vector<double>& A, const std::vector<double>& B, double rel,
                      const std::string& what) {
  ASSERT_EQ(A.size(), B.size());
  double scale = 1e-300, worst = 0.0;
  for (size_t k = 0; k < A.size(); ++k) {
    scale = std::max(scale, std::fabs(B[k]));
    worst = std::max(worst, std::fabs(A[k] - B[k]));
  }
  EXPECT_LE(worst, rel * scale) << what << ": max difference " << worst << " of scale " << scale;
}

class StagesTest : public ::testing::TestWithParam<std::tuple<int, bool>> {};

TEST_P(StagesTest, EquationsOfMotionMatchIndependentLagrangian) {
  const auto& c = kCases[std::get<0>(GetParam())];
  const bool exact = std::get<1>(GetParam());
  auto m = CaseModel(c, exact);
  std::mt19937 rng(7);
  for (int trial = 0; trial < 3; ++trial) {
    RandomState s = MakeRandomState(m.get(), rng);
    std::vector<double> ours(m->nq), h(m->nq), k(m->nq), theirs(m->nq);
    f3r_mass_times(m.get(), s.q.data(), s.a.data(), ours.data());
    f3r_velocity_forces(m.get(), s.q.data(), s.v.data(), h.data());
    f3r_elastic_forces(m.get(), s.q.data(), k.data());
    for (int n = 0; n < m->nq; ++n) ours[n] += h[n] + k[n];
    indep_lagrange(m.get(), s.q.data(), s.v.data(), s.a.data(), theirs.data());
    const double scale = MaxAbs(theirs);
    for (int n = 0; n < m->nq; ++n)
      EXPECT_NEAR(ours[n], theirs[n], 2e-6 * scale) << c.name << " exact=" << exact << " row " << n;
    EXPECT_NEAR(f3r_kinetic_energy(m.get(), s.q.data(), s.v.data()),
                indep_kinetic_energy(m.get(), s.q.data(), s.v.data()), 1e-11);
    EXPECT_NEAR(f3r_potential_energy(m.get(), s.q.data()),
                indep_potential_energy(m.get(), s.q.data()),
                1e-9 * std::max(1e-12, indep_potential_energy(m.get(), s.q.data())));
  }
}

TEST_P(StagesTest, ConstraintsAndTheirDerivativesMatchFiniteDifferences) {
  const auto& c = kCases[std::get<0>(GetParam())];
  auto m = CaseModel(c, std::get<1>(GetParam()));
  const f3r_model* mp = m.get();
  const int nq = m->nq;
  std::mt19937 rng(11);
  RandomState s = MakeRandomState(mp, rng);
  std::vector<double> q(s.q.begin(), s.q.begin() + nq), v(s.v.begin(), s.v.begin() + nq);
  std::vector<double> lambda = {3.0, -2.0, 1.5, 4.0, -0.5, 2.5};

  double g[6], gi[6];
  f3r_constraints(mp, q.data(), g);
  indep_constraints(mp, q.data(), gi);
  for (int r = 0; r < 6; ++r) EXPECT_NEAR(g[r], gi[r], 1e-14);

  auto G = Dense(6, nq,
                 [&](double* A, int ld) { f3r_add_constraint_jacobian(mp, q.data(), 1.0, A, ld); });
  auto Gn = Numeric(
      6, q, nq, [&](const double* x, double* out) { f3r_constraints(mp, x, out); }, 1e-6);
  ExpectMatrixNear(G, Gn, 1e-8, "G");

  auto GT = Dense(nq, 6, [&](double* A, int ld) {
    f3r_add_constraint_jacobian_transpose(mp, q.data(), 1.0, A, ld);
  });
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < nq; ++j) EXPECT_EQ(GT[(size_t)i * nq + j], G[(size_t)j * 6 + i]);

  auto dGTl = Dense(nq, nq, [&](double* A, int ld) {
    f3r_add_constraint_transpose_times_dq(mp, q.data(), lambda.data(), 1.0, A, ld);
  });
  auto dGTl_n = Numeric(
      nq, q, nq,
      [&](const double* x, double* out) {
        f3r_constraint_transpose_times(mp, x, lambda.data(), out);
      },
      1e-6);
  ExpectMatrixNear(dGTl, dGTl_n, 1e-8, "d(G^T lambda)/dq");

  auto dGv = Dense(6, nq, [&](double* A, int ld) {
    f3r_add_constraint_times_dq(mp, q.data(), v.data(), 1.0, A, ld);
  });
  auto dGv_n = Numeric(
      6, q, nq, [&](const double* x, double* out) { f3r_constraint_times(mp, x, v.data(), out); },
      1e-6);
  ExpectMatrixNear(dGv, dGv_n, 1e-8, "d(G v)/dq");

  // gamma = dG/dt v: the derivative of G(q) v along q' = v.
  double gamma[6], gp[6], gm[6];
  f3r_constraint_bias(mp, q.data(), v.data(), gamma);
  const double dt = 1e-6;
  std::vector<double> qp(q), qm(q);
  for (int k = 0; k < nq; ++k) {
    qp[k] += dt * v[k];
    qm[k] -= dt * v[k];
  }
  f3r_constraint_times(mp, qp.data(), v.data(), gp);
  f3r_constraint_times(mp, qm.data(), v.data(), gm);
  for (int r = 0; r < 6; ++r)
    EXPECT_NEAR(gamma[r], (gp[r] - gm[r]) / (2 * dt), 1e-7 * (1 + std::fabs(gamma[r])));

  // d(gamma)/dq and d(gamma)/dv (the minimal formulation's analytic Jacobian needs both).
  auto dgq = Dense(6, nq, [&](double* A, int ld) {
    f3r_add_constraint_bias_dq(mp, q.data(), v.data(), 1.0, A, ld);
  });
  auto dgq_n = Numeric(
      6, q, nq, [&](const double* x, double* out) { f3r_constraint_bias(mp, x, v.data(), out); },
      1e-6);
  ExpectMatrixNear(dgq, dgq_n, 1e-7, "d(gamma)/dq");
  auto dgv = Dense(6, nq, [&](double* A, int ld) {
    f3r_add_constraint_bias_dv(mp, q.data(), v.data(), 1.0, A, ld);
  });
  auto dgv_n = Numeric(
      6, v, nq, [&](const double* x, double* out) { f3r_constraint_bias(mp, q.data(), x, out); },
      1e-6);
  ExpectMatrixNear(dgv, dgv_n, 1e-7, "d(gamma)/dv");
}

TEST_P(StagesTest, InertiaAndForceDerivativesMatchFiniteDifferences) {
  const auto& c = kCases[std::get<0>(GetParam())];
  auto m = CaseModel(c, std::get<1>(GetParam()));
  const f3r_model* mp = m.get();
  const int nq = m->nq;
  std::mt19937 rng(13);
  RandomState s = MakeRandomState(mp, rng);
  std::vector<double> q(s.q.begin(), s.q.begin() + nq), v(s.v.begin(), s.v.begin() + nq),
      a(s.a.begin(), s.a.begin() + nq);

  auto M = Dense(nq, nq, [&](double* A, int ld) { f3r_add_mass_matrix(mp, q.data(), 1.0, A, ld); });
  std::vector<double> Ma(nq);
  f3r_mass_times(mp, q.data(), a.data(), Ma.data());
  for (int i = 0; i < nq; ++i) {
    double s_ = 0.0;
    for (int j = 0; j < nq; ++j) {
      s_ += M[(size_t)j * nq + i] * a[j];
      EXPECT_EQ(M[(size_t)j * nq + i], M[(size_t)i * nq + j]) << "M symmetric";
    }
    EXPECT_NEAR(Ma[i], s_, 1e-12 * (1 + std::fabs(s_)));
  }
  auto dMa = Dense(nq, nq, [&](double* A, int ld) {
    f3r_add_mass_times_dq(mp, q.data(), a.data(), 1.0, A, ld);
  });
  auto dMa_n = Numeric(
      nq, q, nq, [&](const double* x, double* out) { f3r_mass_times(mp, x, a.data(), out); }, 1e-6);
  ExpectMatrixNear(dMa, dMa_n, 1e-8, "d(M a)/dq");

  auto dhq = Dense(nq, nq, [&](double* A, int ld) {
    f3r_add_velocity_forces_dq(mp, q.data(), v.data(), 1.0, A, ld);
  });
  auto dhq_n = Numeric(
      nq, q, nq, [&](const double* x, double* out) { f3r_velocity_forces(mp, x, v.data(), out); },
      1e-6);
  ExpectMatrixNear(dhq, dhq_n, 1e-8, "dh/dq");

  auto dhv = Dense(nq, nq, [&](double* A, int ld) {
    f3r_add_velocity_forces_dv(mp, q.data(), v.data(), 1.0, A, ld);
  });
  auto dhv_n = Numeric(
      nq, v, nq, [&](const double* x, double* out) { f3r_velocity_forces(mp, q.data(), x, out); },
      1e-6);
  ExpectMatrixNear(dhv, dhv_n, 1e-8, "dh/dv");

  auto dk = Dense(nq, nq, [&](double* A, int ld) { f3r_add_elastic_forces_dq(mp, 1.0, A, ld); });
  auto dk_n = Numeric(
      nq, q, nq, [&](const double* x, double* out) { f3r_elastic_forces(mp, x, out); }, 1e-6);
  ExpectMatrixNear(dk, dk_n, 1e-7, "dk/dq");
}

INSTANTIATE_TEST_SUITE_P(AllLinkModels, StagesTest,
                         ::testing::Combine(::testing::Range(0, 7), ::testing::Bool()));

TEST(Stages, AppendixCorrectionOfModalCoriolisForce) {
  // The paper's appendix prints F_c_eta = +rho' th' int psi; the derivation gives
  // -m rho' th' int psi (docs/model.md). h = -F_c, so h_eta must be +m rho' th' b_j.
  auto m = MakeModel(
      SceneWithLinks(F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_FREE, 3));
  std::vector<double> q(F3R_MAX_Q, 0.0), v(F3R_MAX_Q, 0.0), h(F3R_MAX_Q);
  q[0] = 0.12;
  q[3] = 2.0;
  v[0] = 2.0;  // rho_1'
  v[3] = 3.0;  // theta_1'
  f3r_velocity_forces(m.get(), q.data(), v.data(), h.data());
  for (int j = 0; j < 3; ++j)
    EXPECT_NEAR(h[9 + j], m->link_mass * 2.0 * 3.0 * m->link[0].mean[j], 1e-14);
}

TEST(Stages, ModelConstantsFollowTableOne) {
  auto m = MakeModel(f3r_default_scene());
  EXPECT_NEAR(m->link_mass, 0.0356571, 1e-7);
  EXPECT_NEAR(m->bending_stiffness, 35.8338, 1e-4);
  EXPECT_NEAR(m->cylinder_inertia, 2.85861e-4, 1e-9);
  EXPECT_NEAR(m->platform_inertia, 1.6666667e-4, 1e-10);
  // Home pose, eq. (20): rho = 560/sqrt(3) mm - 200 mm, theta = (5, 9, 1) pi/6.
  std::vector<double> q(F3R_MAX_Q, 0.0);
  ASSERT_EQ(f3r_model_close_loops(m.get(), q.data()), F3R_OK);
  const double theta0[3] = {5 * M_PI / 6, 9 * M_PI / 6, M_PI / 6};
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(q[i], 0.560 / std::sqrt(3.0) - 0.2, 1e-12);
    EXPECT_NEAR(std::remainder(q[3 + i] - theta0[i], 2 * M_PI), 0.0, 1e-12);
  }
}

// The event roots close the loops for the leg strokes alone: the same values, to the last bit, as
// the full closure gives (a root that moved by one ulp could move an impact), and the same refusal
// where a leg cannot reach its joint.
TEST(Stages, LegStrokesAloneEqualTheFullClosure) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (f3r_link_model model : {F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_PINNED}) {
    auto m = MakeModel(SceneWithLinks(model, 3, model, 2, model, 4));
    for (int trial = 0; trial < 200; ++trial) {
      std::vector<double> q(F3R_MAX_Q, 0.0);
      q[F3R_Q_X] = 0.05 * u(rng);
      q[F3R_Q_Y] = 0.05 * u(rng);
      q[F3R_Q_PHI] = 0.5 * u(rng);
      for (int n = F3R_Q_MODAL; n < m->nq; ++n) q[n] = 1e-3 * u(rng);
      double rho[3];
      ASSERT_EQ(f3r_fwd_leg_strokes(m.get(), q.data(), rho), F3R_OK);
      ASSERT_EQ(f3r_model_close_loops(m.get(), q.data()), F3R_OK);
      for (int i = 0; i < 3; ++i) EXPECT_EQ(rho[i], q[i]) << "leg " << i << ", trial " << trial;
    }
    double rho[3];
    std::vector<double> onto(F3R_MAX_Q, 0.0); /* the platform joint onto a base joint: singular */
    onto[F3R_Q_X] = m->base_joint[0][0] - m->platform_radius * m->platform_direction[0][0];
    onto[F3R_Q_Y] = m->base_joint[0][1] - m->platform_radius * m->platform_direction[0][1];
    EXPECT_EQ(f3r_fwd_leg_strokes(m.get(), onto.data(), rho), F3R_ERR_SINGULAR);
    EXPECT_EQ(f3r_model_close_loops(m.get(), onto.data()), F3R_ERR_SINGULAR);
  }
}

// The sequencer: the minimal formulation's closed stages at (z, u) and the full stages at the
// (q, v) they close to give the same forward pass (g vanishing), and one call with every stage
// gives what the public (q, v) functions give one by one.
TEST(Stages, ForwardClosedStagesEqualTheFullStages) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const LinkCase& c : kCases) {
    f3r_scene scene = SceneWithLinks(c.a, c.ra, c.b, c.rb, c.c, c.rc, true);
    scene.inputs[F3R_FORCE_RHO].kind = F3R_INPUT_CONSTANT; /* a force stage with an input */
    scene.inputs[F3R_FORCE_RHO].offset = 3.0;
    auto m = MakeModel(scene);
    const int nq = m->nq, nz = m->n_independent;
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<double> z(nz), zd(nz), held(nq);
      z[0] = 0.03 * u(rng), z[1] = 0.03 * u(rng), z[2] = 0.3 * u(rng);
      for (int j = 3; j < nz; ++j) z[j] = 1e-3 * u(rng);
      for (int j = 0; j < nz; ++j) zd[j] = 0.5 * u(rng);
      for (int n = 0; n < nq; ++n) held[n] = u(rng);
      auto closed = std::make_unique<f3r_data>();
      closed->t = 0.1, closed->z = z.data(), closed->u = zd.data(), closed->held = held.data();
      ASSERT_EQ(f3r_forward(m.get(), closed.get(),
                            F3R_FWD_POSITION_CLOSED | F3R_FWD_VELOCITY_CLOSED | F3R_FWD_FORCES |
                                F3R_FWD_ENERGY),
                F3R_OK);
      std::vector<double> q(closed->q, closed->q + nq), v(closed->v, closed->v + nq);
      f3r_fwd_leg_angles(m.get(), closed.get(), q.data());
      auto full = std::make_unique<f3r_data>();
      full->t = 0.1, full->q = q.data(), full->v = v.data(), full->held = held.data();
      ASSERT_EQ(f3r_forward(m.get(), full.get(),
                            F3R_FWD_POSITION | F3R_FWD_VELOCITY | F3R_FWD_FORCES | F3R_FWD_ENERGY),
                F3R_OK);
      for (int k = 0; k < F3R_NCON; ++k) {
        EXPECT_NEAR(full->g[k], 0.0, 1e-13) << c.name;
        EXPECT_NEAR(full->gamma[k], closed->gamma[k], 1e-9) << c.name;
      }
      std::vector<double> h(nq), Q(nq);
      f3r_velocity_forces(m.get(), q.data(), v.data(), h.data());
      f3r_applied_forces(m.get(), 0.1, held.data(), q.data(), v.data(), nullptr, Q.data(), nullptr);
      for (int n = 0; n < nq; ++n) {
        EXPECT_EQ(full->h[n], h[n]) << c.name << " h " << n;
        EXPECT_EQ(full->Q[n], Q[n]) << c.name << " Q " << n;
        EXPECT_NEAR(closed->h[n], h[n], 1e-9 * (1.0 + std::fabs(h[n]))) << c.name;
        EXPECT_NEAR(closed->Q[n], Q[n], 1e-9 * (1.0 + std::fabs(Q[n]))) << c.name;
      }
      EXPECT_EQ(full->kinetic, f3r_kinetic_energy(m.get(), q.data(), v.data())) << c.name;
      EXPECT_EQ(full->potential, f3r_potential_energy(m.get(), q.data())) << c.name;
      EXPECT_NEAR(closed->kinetic, full->kinetic, 1e-12 * (1.0 + full->kinetic)) << c.name;
      EXPECT_NEAR(closed->power, full->power, 1e-9 * (1.0 + std::fabs(full->power))) << c.name;
    }
  }
}

}  // namespace

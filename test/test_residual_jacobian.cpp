// The IDA Jacobian dF/dy + cj dF/dy' of both formulations against finite differences of the
// public residual, at states along a real trajectory.
#include <gtest/gtest.h>

#include "queries.h"
#include "test_support.h"

namespace {

struct Case {
  const char* scene;
  f3r_formulation form;
  bool exact;
  double tolerance;  // relative to the largest entry of the column
  int locks[3];      // legs held at their end stops (equations.h f3r_stop_locks)
};

class ResidualJacobianTest : public ::testing::TestWithParam<Case> {};

TEST_P(ResidualJacobianTest, MatchesFiniteDifferencesOfTheResidual) {
  const Case c = GetParam();
  f3r_scene scene;
  const std::string path = std::string(c.scene).find('/') == std::string::npos
                               ? ScenePath(c.scene)
                               : std::string(F3R_SOURCE_DIR) + "/" + c.scene;
  auto loaded = LoadModel(path, &scene);
  // a scene names what a simulation integrates; index3 is for external solvers only
  scene.formulation = c.form == F3R_FORMULATION_INDEX3 ? F3R_FORMULATION_DAE : c.form;
  scene.exact_kinematics = c.exact;
  auto m = MakeModel(scene);
  // A generic state that closes the loops: moved, turned, deflected and moving.
  const int nq = m->nq, ny = f3r_state_size(m.get(), c.form);
  std::vector<double> q(F3R_MAX_Q, 0.0), v(F3R_MAX_Q, 0.0), y(ny), yp(ny);
  const double pose[3] = {0.01, -0.02, 0.3}, rate[3] = {0.4, -0.3, 3.0};
  for (int k = 0; k < 3; ++k) {
    q[6 + k] = pose[k];
    v[6 + k] = rate[k];
  }
  for (int k = 9; k < nq; ++k) {
    q[k] = 1e-4 * std::sin(3.0 * k);
    v[k] = 1e-2 * std::cos(5.0 * k);
  }
  ASSERT_EQ(f3r_model_close_loops(m.get(), q.data()), F3R_OK);
  f3r_model_close_loop_rates(m.get(), q.data(), v.data());
  WorkspacePtr ws(f3r_workspace_create(m.get()));
  f3r_workspace_set_locks(ws.get(), c.locks);
  const double lag[3] = {1.5, -2.0, 0.7};
  ASSERT_EQ(f3r_consistent_state(m.get(), c.form, 0.013, q.data(), v.data(), nullptr, lag, 0.0,
                                 y.data(), yp.data(), nullptr, ws.get()),
            F3R_OK);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  if (c.form == F3R_FORMULATION_DAE)
    for (int k = 2 * nq + 6; k < 2 * nq + 12; ++k) y[k] = 1e-6 * u(rng);  // mu != 0

  const double cj = 1.7e4;
  std::vector<double> J((size_t)ny * ny);
  ASSERT_EQ(f3r_residual_jacobian(m.get(), c.form, 0.013, cj, y.data(), yp.data(), nullptr,
                                  J.data(), ny, ws.get()),
            F3R_OK);
  std::vector<double> rp(ny), rm(ny), yy(y), ypp(yp);
  for (int j = 0; j < ny; ++j) {
    std::vector<double> col(ny);
    const double h = 1e-6 * std::max(1e-2, std::fabs(y[j]));
    yy = y;
    yy[j] += h;
    ASSERT_EQ(
        f3r_residual(m.get(), c.form, 0.013, yy.data(), yp.data(), nullptr, rp.data(), ws.get()),
        F3R_OK);
    yy[j] -= 2 * h;
    ASSERT_EQ(
        f3r_residual(m.get(), c.form, 0.013, yy.data(), yp.data(), nullptr, rm.data(), ws.get()),
        F3R_OK);
    for (int i = 0; i < ny; ++i) col[i] = (rp[i] - rm[i]) / (2 * h);
    const double hp = 1e-7 * std::max(1.0, std::fabs(yp[j]));
    ypp = yp;
    ypp[j] += hp;
    ASSERT_EQ(
        f3r_residual(m.get(), c.form, 0.013, y.data(), ypp.data(), nullptr, rp.data(), ws.get()),
        F3R_OK);
    ypp[j] -= 2 * hp;
    ASSERT_EQ(
        f3r_residual(m.get(), c.form, 0.013, y.data(), ypp.data(), nullptr, rm.data(), ws.get()),
        F3R_OK);
    for (int i = 0; i < ny; ++i) col[i] += cj * (rp[i] - rm[i]) / (2 * hp);
    double scale = 1e-12;
    for (int i = 0; i < ny; ++i) scale = std::max(scale, std::fabs(col[i]));
    for (int i = 0; i < ny; ++i)
      EXPECT_NEAR(J[(size_t)j * ny + i], col[i], c.tolerance * scale)
          << c.scene << " row " << i << " column " << j;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Formulations, ResidualJacobianTest,
    ::testing::Values(
        Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_DAE, false, 1e-6, {0, 0, 0}},
        Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_DAE, true, 1e-6, {0, 0, 0}},
        Case{"paper_sim3_fixed_pinned.yaml", F3R_FORMULATION_DAE, false, 1e-6, {0, 0, 0}},
        Case{"paper_sim1.yaml", F3R_FORMULATION_DAE, false, 1e-6, {0, 0, 0}},
        Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_MINIMAL, false, 1e-6, {0, 0, 0}},
        Case{"paper_sim3_fixed_pinned.yaml", F3R_FORMULATION_MINIMAL, true, 1e-6, {0, 0, 0}},
        Case{"test/scenes/all_effects.yaml", F3R_FORMULATION_DAE, true, 1e-6, {0, 0, 0}},
        Case{"test/scenes/all_effects.yaml", F3R_FORMULATION_MINIMAL, false, 1e-6, {0, 0, 0}},
        Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_MINIMAL, true, 1e-6, {0, 0, 0}},
        Case{"test/scenes/all_effects.yaml", F3R_FORMULATION_MINIMAL, true, 1e-6, {0, 0, 0}},
        Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_INDEX3, false, 1e-6, {0, 0, 0}},
        Case{"test/scenes/all_effects.yaml", F3R_FORMULATION_INDEX3, true, 1e-6, {0, 0, 0}},
        Case{"test/scenes/sim3_corrected.yaml", F3R_FORMULATION_DAE, false, 1e-6, {0, 0, 0}},
        Case{"test/scenes/sim3_corrected.yaml", F3R_FORMULATION_MINIMAL, true, 1e-6, {0, 0, 0}},
        Case{"test/scenes/sim3_corrected.yaml", F3R_FORMULATION_INDEX3, true, 1e-6, {0, 0, 0}},
        // legs at their stops: the stops' forces' derivative is a central
        // difference quotient (residual.c)
        Case{"test/scenes/all_effects.yaml", F3R_FORMULATION_DAE, true, 1e-6, {1, 0, -1}},
        Case{"test/scenes/all_effects.yaml", F3R_FORMULATION_MINIMAL, true, 1e-6, {1, 1, -1}},
        Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_MINIMAL, false, 1e-6, {0, -1, 0}}));

// The peers' index-3 form: a state made consistent by the constrained solve (LU of
// [M -G^T; G 0]) zeroes every row, and the variables are counted by index as MEBDFI wants them.
TEST(Residual, IndexThreeFormVanishesOnAConsistentStateAndCountsItsVariables) {
  for (const char* name : {"paper_sim3_fixed_free.yaml", "test/scenes/all_effects.yaml"}) {
    f3r_scene scene;
    const std::string path = std::string(name).find('/') == std::string::npos
                                 ? ScenePath(name)
                                 : std::string(F3R_SOURCE_DIR) + "/" + name;
    auto loaded = LoadModel(path, &scene);
    auto m = MakeModel(scene);
    const int nq = m->nq, ny = f3r_state_size(m.get(), F3R_FORMULATION_INDEX3);
    EXPECT_EQ(ny, 2 * nq + 6 + m->n_lag + 1) << name;
    std::vector<double> q(F3R_MAX_Q, 0.0), v(F3R_MAX_Q, 0.0), y(ny), yp(ny), res(ny), id(ny);
    ASSERT_EQ(f3r_model_initial_state(m.get(), q.data(), v.data()), F3R_OK);
    for (int k = 9; k < nq; ++k) v[k] = 1e-2 * std::cos(5.0 * k);
    v[6] = 0.2;
    f3r_model_close_loop_rates(m.get(), q.data(), v.data());
    WorkspacePtr ws(f3r_workspace_create(m.get()));
    const double lag[3] = {1.5, -2.0, 0.7};
    ASSERT_EQ(f3r_consistent_state(m.get(), F3R_FORMULATION_INDEX3, 0.02, q.data(), v.data(),
                                   nullptr, lag, 0.25, y.data(), yp.data(), nullptr, ws.get()),
              F3R_OK);
    ASSERT_EQ(f3r_residual(m.get(), F3R_FORMULATION_INDEX3, 0.02, y.data(), yp.data(), nullptr,
                           res.data(), ws.get()),
              F3R_OK);
    for (int i = 0; i < ny; ++i) EXPECT_NEAR(res[i], 0.0, 1e-9) << name << " row " << i;
    int index_of[F3R_MAX_Q * 2 + 16], counts[3] = {0, 0, 0};
    f3r_index3_variable_indices(m.get(), index_of, counts);
    EXPECT_EQ(counts[0], nq + m->n_lag + 1);
    EXPECT_EQ(counts[1], nq);
    EXPECT_EQ(counts[2], 6);
    f3r_state_kinds(m.get(), F3R_FORMULATION_INDEX3, id.data());
    int seen[3] = {0, 0, 0};
    for (int i = 0; i < ny; ++i) {
      ++seen[index_of[i] - 1];
      EXPECT_EQ(id[i] == 0.0, index_of[i] == 3) << "only the multipliers are algebraic";
    }
    for (int k = 0; k < 3; ++k) EXPECT_EQ(seen[k], counts[k]);
    EXPECT_EQ(y[ny - 1], 0.25);
  }
}

TEST(Residual, StateLayoutHoldsOnlyWhatTheLinksCallFor) {
  const f3r_link_model models[3] = {F3R_LINK_RIGID, F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_FREE};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int c = 0; c < 3; ++c) {
        const int ra = a ? 2 : 0, rb = b ? 3 : 0, rc = c ? 4 : 0;
        auto m = MakeModel(SceneWithLinks(models[a], ra, models[b], rb, models[c], rc));
        EXPECT_EQ(m->nq, 9 + ra + rb + rc);
        EXPECT_EQ(f3r_state_size(m.get(), F3R_FORMULATION_DAE), 2 * (9 + ra + rb + rc) + 13);
        EXPECT_EQ(f3r_state_size(m.get(), F3R_FORMULATION_MINIMAL), 2 * (3 + ra + rb + rc) + 1);
      }
}

// The explicit right-hand side solves the reduced mass B^T M B by its low-rank structure (never
// forming it), or assembled whole by Cholesky; both must give the accelerations of an LU solve of
// the whole constrained system [M -G^T; G 0] at the same state, for rigid, fixed-pinned,
// fixed-free and mixed links, 1 to 20 modes, both kinematics, with every effect on.
TEST(Residual, ExplicitRightHandSideMatchesTheConstrainedSolve) {
  struct Links {
    f3r_link_model a, b, c;
    int ra, rb, rc;
  };
  const Links cases[] = {
      {F3R_LINK_RIGID, F3R_LINK_RIGID, F3R_LINK_RIGID, 0, 0, 0},
      {F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, 3, 3, 3},
      {F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_PINNED, 2, 2, 2},
      {F3R_LINK_FIXED_FREE, F3R_LINK_RIGID, F3R_LINK_FIXED_PINNED, 1, 0, 8},
      {F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_FREE, 8, 5, 1},
      {F3R_LINK_FIXED_FREE, F3R_LINK_FIXED_PINNED, F3R_LINK_FIXED_FREE, 20, 20, 20}};
  for (const Links& l : cases)
    for (int exact = 0; exact < 2; ++exact) {
      f3r_scene scene = SceneWithLinks(l.a, l.ra, l.b, l.rb, l.c, l.rc);
      scene.exact_kinematics = exact;
      scene.gravity[0] = 2.0, scene.gravity[1] = -9.0;
      for (int i = 0; i < 3; ++i) {
        scene.friction_prismatic[i] = 3.0, scene.friction_revolute[i] = 0.2;
        if (scene.links[i].model != F3R_LINK_RIGID) scene.links[i].damping_ratio = 0.02;
      }
      scene.inputs[F3R_FORCE_THETA].kind = F3R_INPUT_CONSTANT;
      scene.inputs[F3R_FORCE_THETA].offset = 1.5;
      auto m = MakeModel(scene);
      const int nq = m->nq, nz = m->n_independent,
                ny = f3r_state_size(m.get(), F3R_FORMULATION_MINIMAL);
      std::vector<double> q(F3R_MAX_Q, 0.0), v(F3R_MAX_Q, 0.0), held(nq, 0.0);
      const double pose[3] = {0.015, -0.01, 0.25}, rate[3] = {-0.3, 0.2, 2.0};
      for (int k = 0; k < 3; ++k) q[F3R_Q_X + k] = pose[k], v[F3R_Q_X + k] = rate[k];
      for (int n = F3R_Q_MODAL; n < nq; ++n)
        q[n] = 2e-4 * std::cos(1.7 * n), v[n] = 3e-2 * std::sin(2.3 * n);
      for (int n = 0; n < nq; ++n) held[n] = 0.7 * std::sin(0.9 * n + 0.3);
      ASSERT_EQ(f3r_model_close_loops(m.get(), q.data()), F3R_OK);
      f3r_model_close_loop_rates(m.get(), q.data(), v.data());
      WorkspacePtr ws(f3r_workspace_create(m.get()));
      std::vector<double> y(ny), yp(ny), structured(ny), dense(ny);
      ASSERT_EQ(
          f3r_consistent_state(m.get(), F3R_FORMULATION_MINIMAL, 0.02, q.data(), v.data(),
                               held.data(), nullptr, 0.0, y.data(), yp.data(), nullptr, ws.get()),
          F3R_OK);
      ASSERT_EQ(f3r_explicit_rhs_solver(m.get(), 1, 0.02, y.data(), held.data(), structured.data(),
                                        ws.get()),
                F3R_OK);
      ASSERT_EQ(
          f3r_explicit_rhs_solver(m.get(), 0, 0.02, y.data(), held.data(), dense.data(), ws.get()),
          F3R_OK);
      // independent: the whole constrained system, LU with pivoting
      std::vector<double> Q(nq), a(nq), lambda(F3R_NCON),
          work(f3r_solve_accelerations_work_size(m.get()));
      f3r_applied_forces(m.get(), 0.02, held.data(), q.data(), v.data(), nullptr, Q.data(),
                         nullptr);
      ASSERT_EQ(f3r_solve_accelerations(m.get(), q.data(), v.data(), Q.data(), a.data(),
                                        lambda.data(), work.data()),
                F3R_OK);
      double scale = 1.0;
      for (int j = 0; j < nz; ++j) scale = std::max(scale, std::fabs(a[F3R_Q_INDEPENDENT + j]));
      for (int j = 0; j < nz; ++j) {
        EXPECT_NEAR(structured[nz + j], a[F3R_Q_INDEPENDENT + j], 1e-10 * scale)
            << "structured, case r " << l.ra << l.rb << l.rc << " exact " << exact << " z " << j;
        EXPECT_NEAR(dense[nz + j], a[F3R_Q_INDEPENDENT + j], 1e-10 * scale)
            << "dense, case r " << l.ra << l.rb << l.rc << " exact " << exact << " z " << j;
        EXPECT_EQ(structured[j], y[nz + j]);
      }
      EXPECT_NEAR(structured[ny - 1], dense[ny - 1], 1e-12 * (1.0 + std::fabs(dense[ny - 1])));
    }
}

// The forward pass computes each angle's sine and cosine once per evaluation: dae one pair per
// leg angle and one for phi_p (rotated onto the three platform joints); minimal only phi_p's,
// since its loop closure gives each leg's direction algebraically. With gravity on (its forces
// need the legs' directions too) and fixed-free links, whose tips enter the constraints.
TEST(Residual, OneEvaluationComputesEachAngleOnce) {
  f3r_scene scene =
      SceneWithLinks(F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_FREE, 3);
  scene.gravity[0] = 3.0;
  scene.gravity[1] = -4.0;
  scene.platform_pose0[2] = 0.2;
  scene.platform_velocity0[0] = 0.3;
  auto m = MakeModel(scene);
  for (f3r_formulation form : {F3R_FORMULATION_DAE, F3R_FORMULATION_MINIMAL}) {
    const int ny = f3r_state_size(m.get(), form);
    std::vector<double> q(F3R_MAX_Q), v(F3R_MAX_Q), y(ny), yp(ny), res(ny), J((size_t)ny * ny);
    ASSERT_EQ(f3r_model_initial_state(m.get(), q.data(), v.data()), F3R_OK);
    WorkspacePtr ws(f3r_workspace_create(m.get()));
    ASSERT_EQ(f3r_consistent_state(m.get(), form, 0.0, q.data(), v.data(), nullptr, nullptr, 0.0,
                                   y.data(), yp.data(), nullptr, ws.get()),
              F3R_OK);
    const long per_evaluation = form == F3R_FORMULATION_DAE ? 4 : 1;
    long before = f3r_workspace_sincos_pairs(ws.get());
    ASSERT_EQ(
        f3r_residual(m.get(), form, 0.001, y.data(), yp.data(), nullptr, res.data(), ws.get()),
        F3R_OK);
    EXPECT_EQ(f3r_workspace_sincos_pairs(ws.get()) - before, per_evaluation)
        << "residual, form " << form;
    if (form == F3R_FORMULATION_MINIMAL) {
      before = f3r_workspace_sincos_pairs(ws.get());
      ASSERT_EQ(f3r_explicit_rhs(m.get(), 0.001, y.data(), nullptr, res.data(), ws.get()), F3R_OK);
      EXPECT_EQ(f3r_workspace_sincos_pairs(ws.get()) - before, 1) << "explicit right-hand side";
    }
    before = f3r_workspace_sincos_pairs(ws.get());
    ASSERT_EQ(f3r_residual_jacobian(m.get(), form, 0.001, 1e4, y.data(), yp.data(), nullptr,
                                    J.data(), ny, ws.get()),
              F3R_OK);
    EXPECT_EQ(f3r_workspace_sincos_pairs(ws.get()) - before, per_evaluation)
        << "Jacobian, form " << form;
  }
}

// A residual with an infinite or NaN entry, in any row (the check sums x * 0.0 in four lanes and a
// tail), is reported as not finite; a large finite one is not.
TEST(Residual, AnEntryThatIsNotFiniteIsReportedInEveryRow) {
  f3r_scene scene =
      SceneWithLinks(F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_FREE, 3);
  auto m = MakeModel(scene);
  for (f3r_formulation form : {F3R_FORMULATION_DAE, F3R_FORMULATION_MINIMAL}) {
    const int ny = f3r_state_size(m.get(), form), nz = m->n_independent;
    std::vector<double> q(F3R_MAX_Q), v(F3R_MAX_Q), y(ny), yp(ny), res(ny);
    ASSERT_EQ(f3r_model_initial_state(m.get(), q.data(), v.data()), F3R_OK);
    WorkspacePtr ws(f3r_workspace_create(m.get()));
    ASSERT_EQ(f3r_consistent_state(m.get(), form, 0.0, q.data(), v.data(), nullptr, nullptr, 0.0,
                                   y.data(), yp.data(), nullptr, ws.get()),
              F3R_OK);
    // rows whose residual is yp minus something: z' - u (minimal) or q' - v (dae), and W' - Q.v
    std::vector<int> rows;
    const int rate_rows = form == F3R_FORMULATION_MINIMAL ? nz : m->nq;
    for (int r = 0; r < rate_rows; ++r) rows.push_back(r);
    rows.push_back(ny - 1);
    for (int row : rows)
      for (double bad : {HUGE_VAL, -HUGE_VAL, std::nan(""), 1e300}) {
        std::vector<double> ypb = yp;
        ypb[row] = bad;
        const f3r_status st =
            f3r_residual(m.get(), form, 0.0, y.data(), ypb.data(), nullptr, res.data(), ws.get());
        EXPECT_EQ(st, std::isfinite(bad) ? F3R_OK : F3R_ERR_NONFINITE)
            << "form " << form << ", row " << row << " of " << ny << ", value " << bad;
      }
  }
}

}  // namespace

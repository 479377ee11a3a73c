// The IDA Jacobian dF/dy + cj dF/dy' of both formulations against finite differences of the
// public residual, at states along a real trajectory.
#include <gtest/gtest.h>

#include "flex3rpr/stages.h"
#include "test_support.h"

namespace {

struct Case {
  const char* scene;
  f3r_formulation form;
  bool exact;
  double tolerance;  // relative to the largest entry of the column
};

class ResidualJacobianTest : public ::testing::TestWithParam<Case> {};

TEST_P(ResidualJacobianTest, MatchesFiniteDifferencesOfTheResidual) {
  const Case c = GetParam();
  f3r_scene scene;
  const std::string path = std::string(c.scene).find('/') == std::string::npos
                               ? ScenePath(c.scene)
                               : std::string(F3R_SOURCE_DIR) + "/" + c.scene;
  auto loaded = LoadModel(path, &scene);
  scene.formulation = c.form;
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
    ASSERT_EQ(f3r_residual(m.get(), c.form, 0.013, yy.data(), yp.data(), nullptr, rp.data(), ws.get()), F3R_OK);
    yy[j] -= 2 * h;
    ASSERT_EQ(f3r_residual(m.get(), c.form, 0.013, yy.data(), yp.data(), nullptr, rm.data(), ws.get()), F3R_OK);
    for (int i = 0; i < ny; ++i) col[i] = (rp[i] - rm[i]) / (2 * h);
    const double hp = 1e-7 * std::max(1.0, std::fabs(yp[j]));
    ypp = yp;
    ypp[j] += hp;
    ASSERT_EQ(f3r_residual(m.get(), c.form, 0.013, y.data(), ypp.data(), nullptr, rp.data(), ws.get()), F3R_OK);
    ypp[j] -= 2 * hp;
    ASSERT_EQ(f3r_residual(m.get(), c.form, 0.013, y.data(), ypp.data(), nullptr, rm.data(), ws.get()), F3R_OK);
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
    ::testing::Values(Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_DAE, false, 1e-6},
                      Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_DAE, true, 1e-6},
                      Case{"paper_sim3_fixed_pinned.yaml", F3R_FORMULATION_DAE, false, 1e-6},
                      Case{"paper_sim1.yaml", F3R_FORMULATION_DAE, false, 1e-6},
                      Case{"paper_sim3_fixed_free.yaml", F3R_FORMULATION_MINIMAL, false, 1e-4},
                      Case{"paper_sim3_fixed_pinned.yaml", F3R_FORMULATION_MINIMAL, true, 1e-4},
                      Case{"test/scenes/all_effects.yaml", F3R_FORMULATION_DAE, true, 1e-6},
                      Case{"test/scenes/all_effects.yaml", F3R_FORMULATION_MINIMAL, false, 1e-4}));

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

// The forward pass computes each angle's sine and cosine once per evaluation: dae one pair per
// leg angle and one for phi_p (rotated onto the three platform joints); minimal only phi_p's,
// since its loop closure gives each leg's direction algebraically. With gravity on (its forces
// need the legs' directions too) and fixed-free links, whose tips enter the constraints.
TEST(Residual, OneEvaluationComputesEachAngleOnce) {
  f3r_scene scene = SceneWithLinks(F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_FREE, 3, F3R_LINK_FIXED_FREE, 3);
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
    ASSERT_EQ(f3r_residual(m.get(), form, 0.001, y.data(), yp.data(), nullptr, res.data(), ws.get()), F3R_OK);
    EXPECT_EQ(f3r_workspace_sincos_pairs(ws.get()) - before, per_evaluation) << "residual, form " << form;
    if (form == F3R_FORMULATION_MINIMAL) {
      before = f3r_workspace_sincos_pairs(ws.get());
      ASSERT_EQ(f3r_explicit_rhs(m.get(), 0.001, y.data(), nullptr, res.data(), ws.get()), F3R_OK);
      EXPECT_EQ(f3r_workspace_sincos_pairs(ws.get()) - before, 1) << "explicit right-hand side";
    } else {
      before = f3r_workspace_sincos_pairs(ws.get());
      ASSERT_EQ(f3r_residual_jacobian(m.get(), form, 0.001, 1e4, y.data(), yp.data(), nullptr, J.data(), ny,
                                      ws.get()),
                F3R_OK);
      EXPECT_EQ(f3r_workspace_sincos_pairs(ws.get()) - before, per_evaluation) << "dae Jacobian";
    }
  }
}

}  // namespace

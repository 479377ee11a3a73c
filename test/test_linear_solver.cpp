// IDA's structured linear solver (src/core/solve/linsol_schur.h) against Eigen's full-pivoting LU of the
// whole iteration matrix dF/dy + cj dF/dy' of both formulations, at states along real
// trajectories, with every effect on; and whole runs with it against runs with SUNDIALS' dense LU.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "linsol_schur.h"
#include "flex3rpr/sim.h"
#include "test_support.h"

namespace {

std::string Path(const char* name) {
  return std::string(name).find('/') == std::string::npos
             ? ScenePath(name)
             : std::string(F3R_SOURCE_DIR) + "/" + name;
}

class SchurLinearSolver : public ::testing::TestWithParam<f3r_formulation> {};

// dae: with mu = 0 (as along exact solutions) the kinematic block is exactly cj I and the
// elimination is exact; the solver's only approximation is dropping d(G^T mu)/dq.
TEST_P(SchurLinearSolver, SolvesTheIterationMatrixAsAFullPivotingLuDoes) {
  const f3r_formulation form = GetParam();
  for (const char* name : {"paper_sim3_fixed_free.yaml", "paper_sim3_fixed_pinned.yaml",
                           "test/scenes/all_effects.yaml", "rigid.yaml"}) {
    f3r_scene scene;
    auto loaded = LoadModel(Path(name), &scene);
    scene.formulation = form;
    auto m = MakeModel(scene);
    f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
    f3r_sim* raw = nullptr;
    f3r_error err{};
    ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    ASSERT_EQ(f3r_sim_advance(sim.get(), 0.037, &err), F3R_OK) << err.message;  // a moving state
    const int ny = f3r_state_size(m.get(), form);
    const int nz = form == F3R_FORMULATION_MINIMAL ? m->n_independent : m->nq;
    std::vector<double> y(f3r_sim_state(sim.get()), f3r_sim_state(sim.get()) + ny), yp(ny, 0.0),
        res(ny);
    WorkspacePtr ws(f3r_workspace_create(m.get()));
    if (form == F3R_FORMULATION_MINIMAL)
      ASSERT_EQ(f3r_explicit_rhs(m.get(), 0.037, y.data(), nullptr, yp.data(), ws.get()), F3R_OK);
    else
      for (int c = 0; c < 6; ++c) y[2 * m->nq + 6 + c] = 0.0;  // mu

    SUNContext ctx = nullptr;
    ASSERT_EQ(SUNContext_Create(nullptr, &ctx), 0);
    SUNMatrix J = SUNDenseMatrix(ny, ny, ctx);
    double cj_now = 0.0;
    SUNLinearSolver ls = f3r_schur_linsol_create(ctx, nz, ny, &cj_now);
    N_Vector b = N_VNew_Serial(ny, ctx), x = N_VNew_Serial(ny, ctx);
    ASSERT_TRUE(J && ls && b && x);
    ASSERT_EQ(SUNLinSolInitialize(ls), SUNLS_SUCCESS);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    for (double cj : {2.0e2, 3.1e4, 6.0e6}) {  // from a slow BDF step to the first step's
      cj_now = cj;
      SUNMatZero(J);
      ASSERT_EQ(f3r_residual_jacobian(m.get(), form, 0.037, cj, y.data(), yp.data(), nullptr,
                                      SM_DATA_D(J), ny, ws.get()),
                F3R_OK);
      Eigen::Map<Eigen::MatrixXd> A(SM_DATA_D(J), ny, ny);
      const Eigen::MatrixXd full = A;  // the solver must not change J
      ASSERT_EQ(SUNLinSolSetup(ls, J), SUNLS_SUCCESS) << name;
      for (int trial = 0; trial < 3; ++trial) {
        Eigen::VectorXd rhs(ny);
        for (int i = 0; i < ny; ++i) rhs[i] = u(rng) * (i < nz ? 1e-3 : 1.0);
        std::copy(rhs.data(), rhs.data() + ny, N_VGetArrayPointer(b));
        ASSERT_EQ(SUNLinSolSolve(ls, J, x, b, 0.0), SUNLS_SUCCESS);
        const Eigen::VectorXd expected = full.fullPivLu().solve(rhs);
        Eigen::Map<Eigen::VectorXd> got(N_VGetArrayPointer(x), ny);
        // J x = b holds: the residual against the whole matrix, independent of the elimination
        EXPECT_LE((full * got - rhs).norm(), 1e-7 * rhs.norm()) << name << " cj " << cj;
        // and the same solution as a full-pivoting LU wherever that LU itself solves well (dae
        // at cj 6e6 with every effect is so ill-conditioned that Eigen's residual is 0.65)
        if ((full * expected - rhs).norm() <= 1e-7 * rhs.norm()) {
          EXPECT_LE((got - expected).norm(), 1e-8 * expected.norm()) << name << " cj " << cj;
        }
        // in place, as IDA may call it (x == b)
        std::copy(rhs.data(), rhs.data() + ny, N_VGetArrayPointer(b));
        ASSERT_EQ(SUNLinSolSolve(ls, J, b, b, 0.0), SUNLS_SUCCESS);
        Eigen::Map<Eigen::VectorXd> in_place(N_VGetArrayPointer(b), ny);
        EXPECT_EQ((in_place - got).norm(), 0.0) << name;
      }
      EXPECT_EQ((A - full).norm(), 0.0);
    }
    N_VDestroy(b);
    N_VDestroy(x);
    SUNLinSolFree(ls);
    SUNMatDestroy(J);
    SUNContext_Free(&ctx);
  }
}

// A whole run: the structured solve changes only Newton's iterates (roundoff for minimal, an
// O(|mu|) term of the iteration matrix for dae), so the path agrees with the dense LU's to well
// within the tolerance, in about as many steps.
TEST_P(SchurLinearSolver, RunsAgreeWithSundialsDenseLu) {
  f3r_scene scene;
  auto loaded = LoadModel(Path("test/scenes/all_effects.yaml"), &scene);
  scene.formulation = GetParam();
  scene.rtol = 1e-8;
  scene.atol = 1e-10;
  auto m = MakeModel(scene);
  f3r_outputs out[2];
  for (int dense = 0; dense < 2; ++dense) {
    f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
    set.dense_linear_solver = dense;
    f3r_sim* raw = nullptr;
    f3r_error err{};
    ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    ASSERT_EQ(f3r_sim_advance(sim.get(), 0.1, &err), F3R_OK) << err.message;
    out[dense] = *f3r_sim_outputs(sim.get());
  }
  for (int n = 0; n < m->nq; ++n) EXPECT_NEAR(out[0].q[n], out[1].q[n], 1e-6) << n;
  EXPECT_NEAR((double)out[0].stats.steps, (double)out[1].stats.steps, 0.1 * out[1].stats.steps);
  EXPECT_GT(out[0].stats.steps, 100);
}

INSTANTIATE_TEST_SUITE_P(Formulations, SchurLinearSolver,
                         ::testing::Values(F3R_FORMULATION_MINIMAL, F3R_FORMULATION_DAE));

}  // namespace

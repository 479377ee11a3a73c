// IDA's structured linear solver for the minimal formulation (src/core/linsol_schur.h) against
// Eigen's full-pivoting LU of the whole iteration matrix dF/dy + cj dF/dy', at states along real
// trajectories, with every effect on; and whole runs with it against runs with SUNDIALS' dense LU.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "../src/core/linsol_schur.h"
#include "flex3rpr/sim.h"
#include "test_support.h"

namespace {

std::string Path(const char* name) {
  return std::string(name).find('/') == std::string::npos ? ScenePath(name)
                                                          : std::string(F3R_SOURCE_DIR) + "/" + name;
}

TEST(SchurLinearSolver, SolvesTheIterationMatrixAsAFullPivotingLuDoes) {
  for (const char* name : {"paper_sim3_fixed_free.yaml", "paper_sim3_fixed_pinned.yaml",
                           "test/scenes/all_effects.yaml", "rigid.yaml"}) {
    f3r_scene scene;
    auto loaded = LoadModel(Path(name), &scene);
    scene.formulation = F3R_FORMULATION_MINIMAL;
    auto m = MakeModel(scene);
    f3r_solver_settings set = f3r_solver_settings_from_scene(&scene);
    f3r_sim* raw = nullptr;
    f3r_error err{};
    ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    ASSERT_EQ(f3r_sim_advance(sim.get(), 0.037, &err), F3R_OK) << err.message;  // a moving state
    const int ny = f3r_state_size(m.get(), F3R_FORMULATION_MINIMAL), nz = m->n_independent;
    std::vector<double> y(f3r_sim_state(sim.get()), f3r_sim_state(sim.get()) + ny), yp(ny), res(ny);
    WorkspacePtr ws(f3r_workspace_create(m.get()));
    ASSERT_EQ(f3r_explicit_rhs(m.get(), 0.037, y.data(), nullptr, yp.data(), ws.get()), F3R_OK);

    SUNContext ctx = nullptr;
    ASSERT_EQ(SUNContext_Create(nullptr, &ctx), 0);
    SUNMatrix J = SUNDenseMatrix(ny, ny, ctx);
    SUNLinearSolver ls = f3r_schur_linsol_create(ctx, nz, ny);
    N_Vector b = N_VNew_Serial(ny, ctx), x = N_VNew_Serial(ny, ctx);
    ASSERT_TRUE(J && ls && b && x);
    ASSERT_EQ(SUNLinSolInitialize(ls), SUNLS_SUCCESS);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    for (double cj : {2.0e2, 3.1e4, 6.0e6}) {  // from a slow BDF step to the first step's
      SUNMatZero(J);
      ASSERT_EQ(f3r_residual_jacobian(m.get(), F3R_FORMULATION_MINIMAL, 0.037, cj, y.data(),
                                      yp.data(), nullptr, SM_DATA_D(J), ny, ws.get()),
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
        EXPECT_LE((got - expected).norm(), 1e-10 * expected.norm()) << name << " cj " << cj;
        // in place, as IDA may call it (x == b)
        std::copy(rhs.data(), rhs.data() + ny, N_VGetArrayPointer(b));
        ASSERT_EQ(SUNLinSolSolve(ls, J, b, b, 0.0), SUNLS_SUCCESS);
        Eigen::Map<Eigen::VectorXd> in_place(N_VGetArrayPointer(b), ny);
        EXPECT_LE((in_place - expected).norm(), 1e-10 * expected.norm()) << name;
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

// A whole run: the structured solve changes only roundoff in Newton's iterates, so the path
// agrees with the dense LU's to well within the tolerance, in about as many steps.
TEST(SchurLinearSolver, RunsAgreeWithSundialsDenseLu) {
  f3r_scene scene;
  auto loaded = LoadModel(Path("test/scenes/all_effects.yaml"), &scene);
  scene.formulation = F3R_FORMULATION_MINIMAL;
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

}  // namespace

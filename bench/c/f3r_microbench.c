/* Nanoseconds per residual, per Jacobian and per explicit right-hand side (minimal) of both
 * formulations, for r = 1, 3, 8 and 20 fixed-free modes per link, at a generic moving state, and
 * the sin/cos pairs of one residual; then IDA's linear solver on the minimal formulation's
 * iteration matrix, SUNDIALS' dense LU against the Schur complement (linsol_schur.h): ns per
 * setup (factorisation) and per solve. Prints two Markdown tables.
 *   f3r_microbench [repetitions]
 * The source also links against a core without the sin/cos counter (an older build, for a
 * before/after comparison in one run): that column then says n/a. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "linsol_schur.h"
#include "model_layout.h"
#include "residual.h"
#include "queries.h"

/* weak: absent from cores built before the forward pass */
extern long f3r_workspace_sincos_pairs(const f3r_workspace* ws) __attribute__((weak));
extern f3r_status f3r_explicit_rhs_solver(const f3r_model* model, int structured, double t,
                                          const double* y, const double* held, double* ydot,
                                          f3r_workspace* ws) __attribute__((weak));

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* ns per setup and per solve of one linear solver on the iteration matrix J0 (ny x ny). */
static void time_linear_solver(SUNLinearSolver ls, SUNMatrix J, const double* J0, int ny,
                               N_Vector b, N_Vector x, long reps, double* setup_ns,
                               double* solve_ns) {
  SUNLinSolInitialize(ls);
  const long sreps = reps / 20 + 1;
  double t0 = now();
  for (long r = 0; r < sreps; ++r) {
    for (long k = 0; k < (long)ny * ny; ++k) SM_DATA_D(J)[k] = J0[k];
    SUNLinSolSetup(ls, J);
  }
  const double copy0 = now();
  for (long r = 0; r < sreps; ++r)
    for (long k = 0; k < (long)ny * ny; ++k) SM_DATA_D(J)[k] = J0[k] + 1e-300 * r;
  const double copy_s = now() - copy0; /* the matrix copy is not the solver's: subtract it */
  *setup_ns = (now() - t0 - 2 * copy_s) / sreps * 1e9;
  for (long k = 0; k < (long)ny * ny; ++k) SM_DATA_D(J)[k] = J0[k];
  SUNLinSolSetup(ls, J);
  double* bb = N_VGetArrayPointer(b);
  t0 = now();
  for (long r = 0; r < reps; ++r) {
    bb[r % ny] += 1e-3;
    SUNLinSolSolve(ls, J, x, b, 0.0);
  }
  *solve_ns = (now() - t0) / reps * 1e9;
}

static void linear_solver_table(long reps) {
  const int modes[] = {1, 3, 8, 20};
  printf(
      "\n| modes per link (minimal) | state size | dense LU setup / solve (ns) | Schur setup / "
      "solve (ns) |\n");
  printf("|---|---:|---:|---:|\n");
  SUNContext ctx = NULL;
  if (SUNContext_Create(NULL, &ctx) != 0) return;
  for (int k = 0; k < 4; ++k) {
    f3r_scene s = f3r_default_scene();
    for (int i = 0; i < 3; ++i) {
      s.links[i].model = F3R_LINK_FIXED_FREE;
      s.links[i].modes = modes[k];
    }
    s.platform_velocity0[0] = 0.3;
    f3r_model* m = NULL;
    f3r_error err;
    if (f3r_model_create(&s, &m, &err) != F3R_OK) continue;
    const int ny = f3r_state_size(m, F3R_FORMULATION_MINIMAL);
    double q[F3R_MAX_Q] = {0}, v[F3R_MAX_Q] = {0};
    f3r_model_initial_state(m, q, v);
    f3r_workspace* ws = f3r_workspace_create(m);
    double* y = calloc((size_t)ny, sizeof(double));
    double* yp = calloc((size_t)ny, sizeof(double));
    double* J0 = calloc((size_t)ny * ny, sizeof(double));
    f3r_consistent_state(m, F3R_FORMULATION_MINIMAL, 0.0, q, v, NULL, NULL, 0.0, y, yp, NULL, ws);
    f3r_residual_jacobian(m, F3R_FORMULATION_MINIMAL, 0.0, 3e4, y, yp, NULL, J0, ny, ws);
    SUNMatrix J = SUNDenseMatrix(ny, ny, ctx);
    N_Vector b = N_VNew_Serial(ny, ctx), x = N_VNew_Serial(ny, ctx);
    N_VConst(1.0, b);
    SUNLinearSolver dense = SUNLinSol_Dense(b, J, ctx);
    const double cj = 3e4;
    SUNLinearSolver schur = f3r_schur_linsol_create(ctx, m->n_independent, ny, &cj);
    double ns[4];
    time_linear_solver(dense, J, J0, ny, b, x, reps, &ns[0], &ns[1]);
    time_linear_solver(schur, J, J0, ny, b, x, reps, &ns[2], &ns[3]);
    printf("| r = %d | %d | %.0f / %.0f | %.0f / %.0f |\n", modes[k], ny, ns[0], ns[1], ns[2],
           ns[3]);
    SUNLinSolFree(dense);
    SUNLinSolFree(schur);
    N_VDestroy(b);
    N_VDestroy(x);
    SUNMatDestroy(J);
    free(y), free(yp), free(J0);
    f3r_workspace_destroy(ws);
    f3r_model_destroy(m);
  }
  SUNContext_Free(&ctx);
}

/* Paper-like scene with `modes` fixed-free modes per link, moving and harmonically forced. */
static f3r_scene bench_scene(int modes) {
  f3r_scene s = f3r_default_scene();
  for (int i = 0; i < 3; ++i) {
    s.links[i].model = F3R_LINK_FIXED_FREE;
    s.links[i].modes = modes;
  }
  s.platform_pose0[0] = 0.01;
  s.platform_velocity0[0] = 0.3;
  s.platform_velocity0[2] = 2.0;
  s.inputs[0].kind = F3R_INPUT_HARMONIC;
  s.inputs[0].amplitude = 5.0;
  s.inputs[0].omega = 100.0;
  return s;
}

/* ns per explicit right-hand side (minimal) into rhs, and with the low-rank / dense Cholesky solver
 * into rhs_dense ("n/a" when the core lacks f3r_explicit_rhs_solver). */
static double time_explicit_rhs(const f3r_model* m, const double* y, double* res, f3r_workspace* ws,
                                long reps, char* rhs, char* rhs_dense, size_t size) {
  double sink = 0.0;
  const long rreps = reps / 4 + 1;
  double t0 = now();
  for (long r = 0; r < rreps; ++r) {
    f3r_explicit_rhs(m, 1e-9 * r, y, NULL, res, ws);
    sink += res[0];
  }
  snprintf(rhs, size, "%.0f", (now() - t0) / rreps * 1e9);
  snprintf(rhs_dense, size, "n/a");
  if (f3r_explicit_rhs_solver) {
    double ns[2];
    for (int arrow = 1; arrow >= 0; --arrow) {
      t0 = now();
      for (long r = 0; r < rreps; ++r) {
        f3r_explicit_rhs_solver(m, arrow, 1e-9 * r, y, NULL, res, ws);
        sink += res[0];
      }
      ns[arrow] = (now() - t0) / rreps * 1e9;
    }
    snprintf(rhs_dense, size, "%.0f / %.0f", ns[1], ns[0]);
  }
  return sink;
}

/* One row of the first table: formulation `form` of model m at a generic moving state. The
 * names are spelled here, not taken from scene.h, so that the bench still links against older
 * cores. */
static void bench_row(const f3r_model* m, const f3r_scene* s, int form, int modes, long reps) {
  const int ny = f3r_state_size(m, (f3r_formulation)form);
  double q[F3R_MAX_Q] = {0}, v[F3R_MAX_Q] = {0};
  for (int n = 6; n < 9; ++n) {
    q[n] = s->platform_pose0[n - 6];
    v[n] = s->platform_velocity0[n - 6];
  }
  for (int n = 9; n < m->nq; ++n) {
    q[n] = 1e-4 * sin(n);
    v[n] = 1e-2 * cos(n);
  }
  f3r_model_close_loops(m, q);
  f3r_model_close_loop_rates(m, q, v);
  f3r_workspace* ws = f3r_workspace_create(m);
  double* y = calloc((size_t)ny, sizeof(double));
  double* yp = calloc((size_t)ny, sizeof(double));
  double* res = calloc((size_t)ny, sizeof(double));
  double* J = calloc((size_t)ny * ny, sizeof(double));
  f3r_consistent_state(m, (f3r_formulation)form, 0.0, q, v, NULL, NULL, 0.0, y, yp, NULL, ws);
  double sink = 0.0;
  char pairs[32] = "n/a";
  if (f3r_workspace_sincos_pairs) {
    const long before = f3r_workspace_sincos_pairs(ws);
    f3r_residual(m, (f3r_formulation)form, 0.0, y, yp, NULL, res, ws);
    snprintf(pairs, sizeof pairs, "%ld", f3r_workspace_sincos_pairs(ws) - before);
  }
  double t0 = now();
  for (long r = 0; r < reps; ++r) {
    f3r_residual(m, (f3r_formulation)form, 1e-9 * r, y, yp, NULL, res, ws);
    sink += res[0];
  }
  const double residual_ns = (now() - t0) / reps * 1e9;
  const long jreps = reps / (form == 0 ? 20 : 200) + 1;
  t0 = now();
  for (long r = 0; r < jreps; ++r) {
    f3r_residual_jacobian(m, (f3r_formulation)form, 0.0, 1e4, y, yp, NULL, J, ny, ws);
    sink += J[0];
  }
  const double jacobian_ns = (now() - t0) / jreps * 1e9;
  char rhs[32] = "", rhs_dense[32] = "";
  if (form == F3R_FORMULATION_MINIMAL)
    sink += time_explicit_rhs(m, y, res, ws, reps, rhs, rhs_dense, sizeof rhs);
  printf("| %d | %s | %d | %.0f | %.0f | %s | %s | %s |\n", modes, form ? "minimal" : "dae", ny,
         residual_ns, jacobian_ns, rhs, rhs_dense, pairs);
  if (sink == 12345.678) printf(" ");
  free(y), free(yp), free(res), free(J);
  f3r_workspace_destroy(ws);
}

int main(int argc, char** argv) {
  const long reps = argc > 1 ? atol(argv[1]) : 200000;
  const int modes[] = {1, 3, 8, 20};
  printf(
      "| modes per link | formulation | state size | residual (ns) | Jacobian (ns) | explicit RHS "
      "(ns) | explicit RHS, low-rank / dense Cholesky (ns) | sin/cos pairs per residual |\n");
  printf("|---:|---|---:|---:|---:|---:|---:|---:|\n");
  for (int k = 0; k < 4; ++k) {
    const f3r_scene s = bench_scene(modes[k]);
    f3r_model* m = NULL;
    f3r_error err;
    if (f3r_model_create(&s, &m, &err) != F3R_OK) {
      fprintf(stderr, "%s\n", err.message);
      return 1;
    }
    for (int form = 0; form < 2; ++form) bench_row(m, &s, form, modes[k], reps);
    f3r_model_destroy(m);
  }
  linear_solver_table(reps);
  return 0;
}

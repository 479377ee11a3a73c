/* ARKODE ARKStep back end, implicit only: the minimal formulation as an ODE y' = f(t, y),
 * integrated by a diagonally implicit Runge-Kutta table (ARKODE's ESDIRK tables; default
 * Kvaerno 7(4,5), L-stable). A-stable tables stay stable on the imaginary axis, where the
 * undamped elastic modes put their eigenvalues, at any step; they pay for it with a Newton
 * iteration per stage. Newton uses a dense LU with a forward-difference Jacobian of f computed
 * here into the stepper's own vectors (ARKODE's allocates a vector on every evaluation). What
 * it shares with the ERK back end (options, restart, advance) is in stepper.c. */
#include <arkode/arkode_arkstep.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "stepper.h"

#define F3R_DIRK_DEFAULT_TABLE "ARKODE_KVAERNO_7_4_5"

static void dirk_counters(const f3r_stepper* st, f3r_sim_stats* raw);

static const f3r_arkode_calls dirk_calls = F3R_ARKODE_CALLS(ARKStep, dirk_counters);

/* df/dy by forward differences, column j into J's column j: ny right-hand sides. */
static int jacobian_fn(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user, N_Vector t1,
                       N_Vector t2, N_Vector t3) {
  (void)t2, (void)t3;
  f3r_stepper* st = user;
  const int ny = (int)N_VGetLength(y);
  const double* y0 = N_VGetArrayPointer(y);
  const double* f0 = N_VGetArrayPointer(fy);
  double* yy = N_VGetArrayPointer(t1);
  memcpy(yy, y0, (size_t)ny * sizeof(double));
  const double root_eps = sqrt(DBL_EPSILON);
  for (int j = 0; j < ny; ++j) {
    const double h = root_eps * fmax(fabs(y0[j]), st->settings.atol / st->settings.rtol);
    yy[j] = y0[j] + h;
    double* col = SM_COLUMN_D(J, j);
    const f3r_status s =
        f3r_explicit_rhs(st->model, f3r_stepper_force_time(st, t), yy, st->held, col, st->ws);
    st->jacobian_rhs_evals++;
    st->residual_calls++;
    if (s != F3R_OK) {
      st->recoverable++;
      return 1;
    }
    const double inv_h = 1.0 / (yy[j] - y0[j]);
    for (int i = 0; i < ny; ++i) col[i] = (col[i] - f0[i]) * inv_h;
    yy[j] = y0[j];
  }
  return 0;
}

#define CHECK(call) F3R_STEPPER_CHECK(call, ARKStepGetReturnFlagName)

static f3r_status dirk_setup(f3r_stepper* st, N_Vector y, N_Vector yp, double t0, f3r_error* err) {
  (void)yp;
  ARKodeButcherTable table;
  const f3r_status s = f3r_stepper_explicit_start(st, t0, 1, F3R_DIRK_DEFAULT_TABLE, &table, err);
  if (s != F3R_OK) return s;
  st->mem = ARKStepCreate(NULL, f3r_stepper_explicit_rhs, t0, y, st->ctx);
  if (!st->mem) {
    ARKodeButcherTable_Free(table);
    return f3r_error_set(err, F3R_ERR_SOLVER, "ARKStepCreate failed");
  }
  /* ARKStep keeps a copy */
  const int flag = ARKStepSetTables(st->mem, table->q, table->p, table, NULL);
  ARKodeButcherTable_Free(table);
  CHECK(flag);
  const f3r_status configured = f3r_arkode_configure(st, &dirk_calls, err);
  if (configured != F3R_OK) return configured;
  const int ny = (int)N_VGetLength(y);
  st->J = SUNDenseMatrix(ny, ny, st->ctx);
  if (!st->J) return f3r_error_set(err, F3R_ERR_MEMORY, "SUNDenseMatrix failed");
  st->ls = SUNLinSol_Dense(y, st->J, st->ctx);
  if (!st->ls) return f3r_error_set(err, F3R_ERR_MEMORY, "SUNLinSol_Dense failed");
  CHECK(ARKStepSetLinearSolver(st->mem, st->ls, st->J));
  CHECK(ARKStepSetJacFn(st->mem, jacobian_fn));
  return F3R_OK;
}

static void dirk_counters(const f3r_stepper* st, f3r_sim_stats* raw) {
  long nfe = 0, nfi = 0, nje = 0, nfi_ls = 0, nncf = 0;
  /* a failed getter leaves its counter at 0 rather than garbage */
  if (ARKStepGetNumRhsEvals(st->mem, &nfe, &nfi) < 0) nfe = nfi = 0;
  if (ARKStepGetNumJacEvals(st->mem, &nje) < 0) nje = 0;
  if (ARKStepGetNumLinRhsEvals(st->mem, &nfi_ls) < 0) nfi_ls = 0;
  if (ARKStepGetNumNonlinSolvConvFails(st->mem, &nncf) < 0) nncf = 0;
  f3r_arkode_counters(st, raw);
  raw->residual_evals = nfe + nfi + nfi_ls + st->jacobian_rhs_evals;
  raw->jacobian_evals = nje;
  raw->nonlinear_failures = nncf;
  raw->last_order = 0;
}

static void dirk_release(f3r_stepper* st) {
  if (st->mem) ARKStepFree(&st->mem);
  if (st->ls) SUNLinSolFree(st->ls);
  if (st->J) SUNMatDestroy(st->J);
  st->ls = NULL;
  st->J = NULL;
}

const f3r_stepper_ops f3r_dirk_stepper = {dirk_setup, f3r_arkode_restart, f3r_arkode_advance,
                                          f3r_arkode_stats, dirk_release};

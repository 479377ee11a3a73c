/* ARKODE ARKStep back end, implicit only: the minimal formulation as an ODE y' = f(t, y),
 * integrated by a diagonally implicit Runge-Kutta table (ARKODE's ESDIRK tables; default
 * Kvaerno 7(4,5), L-stable). A-stable tables stay stable on the imaginary axis, where the
 * undamped elastic modes put their eigenvalues, at any step; they pay for it with a Newton
 * iteration per stage. Newton uses a dense LU with a forward-difference Jacobian of f computed
 * here into the stepper's own vectors (ARKODE's allocates a vector on every evaluation). */
#include <arkode/arkode_arkstep.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "stepper.h"

#define F3R_DIRK_DEFAULT_TABLE "ARKODE_KVAERNO_7_4_5"

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

static f3r_status failed(f3r_stepper* st, f3r_error* err, const char* call, int flag) {
  return f3r_error_set(err, F3R_ERR_SOLVER, "%s failed: %s (%s)", call,
                       ARKStepGetReturnFlagName(flag), st->message);
}

#define CHECK(call)                                      \
  do {                                                   \
    const int flag_ = (call);                            \
    if (flag_ < 0) return failed(st, err, #call, flag_); \
  } while (0)

static f3r_status dirk_setup(f3r_stepper* st, N_Vector y, N_Vector yp, double t0, f3r_error* err) {
  (void)yp;
  st->t_segment = t0;
  if (st->settings.formulation != F3R_FORMULATION_MINIMAL)
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "solver.integrator: dirk needs the minimal formulation, not dae");
  const char* name = st->settings.rk_table[0] ? st->settings.rk_table : F3R_DIRK_DEFAULT_TABLE;
  ARKodeButcherTable table = f3r_stepper_load_table(1, name);
  if (!table)
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "solver.table: '%s' is not a diagonally implicit table", name);
  st->mem = ARKStepCreate(NULL, f3r_stepper_explicit_rhs, t0, y, st->ctx);
  if (!st->mem) {
    ARKodeButcherTable_Free(table);
    return f3r_error_set(err, F3R_ERR_SOLVER, "ARKStepCreate failed");
  }
  /* ARKStep keeps a copy */
  const int flag = ARKStepSetTables(st->mem, table->q, table->p, table, NULL);
  ARKodeButcherTable_Free(table);
  CHECK(flag);
  CHECK(ARKStepSetErrHandlerFn(st->mem, f3r_stepper_error_handler, st));
  CHECK(ARKStepSStolerances(st->mem, st->settings.rtol, st->settings.atol));
  CHECK(ARKStepSetUserData(st->mem, st));
  CHECK(ARKStepSetMaxNumSteps(st->mem, 100000000L));
  CHECK(ARKStepSetInterpolantDegree(st->mem, 3)); /* see stepper_erk.c */
  if (st->settings.max_step > 0.0) CHECK(ARKStepSetMaxStep(st->mem, st->settings.max_step));
  const int ny = (int)N_VGetLength(y);
  st->J = SUNDenseMatrix(ny, ny, st->ctx);
  if (!st->J) return f3r_error_set(err, F3R_ERR_MEMORY, "SUNDenseMatrix failed");
  st->ls = SUNLinSol_Dense(y, st->J, st->ctx);
  if (!st->ls) return f3r_error_set(err, F3R_ERR_MEMORY, "SUNLinSol_Dense failed");
  CHECK(ARKStepSetLinearSolver(st->mem, st->ls, st->J));
  CHECK(ARKStepSetJacFn(st->mem, jacobian_fn));
  int directions[F3R_NROOTS];
  for (int k = 0; k < F3R_NROOTS; ++k) directions[k] = -1;
  CHECK(ARKStepRootInit(st->mem, F3R_NROOTS, f3r_stepper_explicit_roots));
  CHECK(ARKStepSetRootDirection(st->mem, directions));
  return F3R_OK;
}

static void dirk_stats(const f3r_stepper* st, f3r_sim_stats* out) {
  long nst = 0, nfe = 0, nfi = 0, netf = 0, nje = 0, nfi_ls = 0, nncf = 0;
  realtype hlast = 0.0;
  /* a failed getter leaves its counter at 0 rather than garbage */
  if (ARKStepGetNumSteps(st->mem, &nst) < 0) nst = 0;
  if (ARKStepGetNumRhsEvals(st->mem, &nfe, &nfi) < 0) nfe = nfi = 0;
  if (ARKStepGetNumErrTestFails(st->mem, &netf) < 0) netf = 0;
  if (ARKStepGetNumJacEvals(st->mem, &nje) < 0) nje = 0;
  if (ARKStepGetNumLinRhsEvals(st->mem, &nfi_ls) < 0) nfi_ls = 0;
  if (ARKStepGetNumNonlinSolvConvFails(st->mem, &nncf) < 0) nncf = 0;
  if (ARKStepGetLastStep(st->mem, &hlast) < 0) hlast = 0.0;
  *out = st->base;
  out->steps += nst;
  out->residual_evals += nfe + nfi + nfi_ls + st->jacobian_rhs_evals;
  out->jacobian_evals += nje;
  out->error_test_failures += netf;
  out->nonlinear_failures += nncf;
  out->recoverable_errors = st->recoverable;
  out->last_step = hlast;
  out->last_order = 0;
}

static f3r_status dirk_restart(f3r_stepper* st, N_Vector y, N_Vector yp, double t, f3r_error* err) {
  (void)yp;
  dirk_stats(st, &st->base);
  st->jacobian_rhs_evals = 0; /* now in base */
  st->base.restarts++;
  CHECK(ARKStepReset(st->mem, t, y));
  st->t_segment = t;
  return F3R_OK;
}

static f3r_status dirk_advance(f3r_stepper* st, double tout, double tstop, N_Vector y, N_Vector yp,
                               double* t_reached, int* event, f3r_error* err) {
  (void)yp; /* y' costs a right-hand side: the simulation evaluates it when outputs need it */
  CHECK(ARKStepSetStopTime(st->mem, tstop)); /* see stepper_ida.c */
  realtype t = *t_reached;
  const int flag = ARKStepEvolve(st->mem, tout, y, &t, ARK_NORMAL);
  *t_reached = t;
  *event = flag == ARK_ROOT_RETURN;
  st->yp_stale = 1;
  if (*event) CHECK(ARKStepGetRootInfo(st->mem, st->root_info));
  if (flag >= 0) return F3R_OK;
  (void)ARKStepGetDky(st->mem, t, 0, y); /* the last good state, as stepper_erk.c */
  return f3r_error_set(err, flag == ARK_RHSFUNC_FAIL ? F3R_ERR_NONFINITE : F3R_ERR_SOLVER,
                       "ARKStepEvolve stopped at t = %.9g before %.9g: %s (%s)", t, tout,
                       ARKStepGetReturnFlagName(flag), st->message);
}

static void dirk_release(f3r_stepper* st) {
  if (st->mem) ARKStepFree(&st->mem);
  if (st->ls) SUNLinSolFree(st->ls);
  if (st->J) SUNMatDestroy(st->J);
  st->ls = NULL;
  st->J = NULL;
}

const f3r_stepper_ops f3r_dirk_stepper = {dirk_setup, dirk_restart, dirk_advance, dirk_stats,
                                          dirk_release};

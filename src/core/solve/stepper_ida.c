/* IDA back end: analytic (or difference-quotient) Jacobian, algebraic unknowns marked and
 * suppressed from the error test. The linear solver is the Schur complement on the kinematic
 * rows (linsol_schur.h) with the analytic Jacobian, else SUNDIALS' dense LU. Every SUNDIALS
 * call is checked. */
#include <ida/ida.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "linsol_schur.h"
#include "stepper.h"
#include "model_layout.h"

/* The algebraic unknowns (lambda, mu) are not in the error test, but their weights enter IDA's
 * Newton convergence test. In an index-2 system they are only determined to about
 * M eps |q| / h^2 (lambda) and eps |q| / h (mu): roundoff in g(q) amplified by the step. Weights
 * tighter than that make Newton fail at the first step. Measured on the four paper scenes at
 * rtol 1e-10..1e-12: a floor of 1e-8 still fails on two, 1e-6 passes all; without the floor
 * every scene fails at rtol 1e-12. Multipliers are forces (N), so they also scale with atol. */
#define F3R_ALGEBRAIC_ATOL_SCALE 1e4
#define F3R_ALGEBRAIC_ATOL_MIN 1e-6
/* The first step is given explicitly: IDA's own estimate assumes an index-1 start. */
#define F3R_INITIAL_STEP 1e-7

/* 1 when IDA solves with the Schur complement (linsol_schur.h) under these settings. */
static int uses_schur(const f3r_solver_settings* s) {
  return (s->formulation == F3R_FORMULATION_MINIMAL || s->formulation == F3R_FORMULATION_DAE) &&
         s->analytic_jacobian && !s->dense_linear_solver;
}

static int residual_fn(realtype t, N_Vector y, N_Vector yp, N_Vector res, void* user) {
  f3r_stepper* st = user;
  st->residual_calls++;
  const f3r_status s =
      f3r_residual(st->model, st->settings.formulation, t, N_VGetArrayPointer(y),
                   N_VGetArrayPointer(yp), st->held, N_VGetArrayPointer(res), st->ws);
  if (s == F3R_OK) return 0;
  st->recoverable++;
  return 1; /* recoverable: IDA cuts the step */
}

static int jacobian_fn(realtype t, realtype cj, N_Vector y, N_Vector yp, N_Vector r, SUNMatrix J,
                       void* user, N_Vector t1, N_Vector t2, N_Vector t3) {
  (void)r, (void)t1, (void)t2, (void)t3;
  f3r_stepper* st = user;
  st->jacobian_cj = cj;
  const f3r_status s = f3r_residual_jacobian(st->model, st->settings.formulation, t, cj,
                                             N_VGetArrayPointer(y), N_VGetArrayPointer(yp),
                                             st->held, SM_DATA_D(J), (int)SM_ROWS_D(J), st->ws);
  if (s == F3R_OK) return 0;
  st->recoverable++;
  return 1;
}

static int root_fn(realtype t, N_Vector y, N_Vector yp, realtype* g, void* user) {
  (void)yp;
  return f3r_stepper_roots(user, t, N_VGetArrayPointer(y), g);
}

#define CHECK(call) F3R_STEPPER_CHECK(call, IDAGetReturnFlagName)

static f3r_status ida_setup(f3r_stepper* st, N_Vector y, N_Vector yp, double t0, f3r_error* err) {
  const f3r_model* m = st->model;
  const int ny = (int)N_VGetLength(y);
  st->mem = IDACreate(st->ctx);
  if (!st->mem) return f3r_error_set(err, F3R_ERR_SOLVER, "IDACreate failed");
  CHECK(IDASetErrHandlerFn(st->mem, f3r_stepper_error_handler, st));
  CHECK(IDAInit(st->mem, residual_fn, t0, y, yp));
  st->id = N_VNew_Serial(ny, st->ctx);
  st->atol = N_VNew_Serial(ny, st->ctx);
  if (!st->id || !st->atol) return f3r_error_set(err, F3R_ERR_MEMORY, "N_VNew_Serial failed");
  f3r_state_kinds(m, st->settings.formulation, N_VGetArrayPointer(st->id));
  double* atol = N_VGetArrayPointer(st->atol);
  for (int n = 0; n < ny; ++n) atol[n] = st->settings.atol;
  if (st->settings.formulation == F3R_FORMULATION_DAE)
    for (int c = 0; c < 2 * F3R_NCON; ++c)
      atol[2 * m->nq + c] =
          fmax(st->settings.atol * F3R_ALGEBRAIC_ATOL_SCALE, F3R_ALGEBRAIC_ATOL_MIN);
  CHECK(IDASVtolerances(st->mem, st->settings.rtol, st->atol));
  CHECK(IDASetUserData(st->mem, st));
  CHECK(IDASetId(st->mem, st->id));
  if (st->settings.formulation == F3R_FORMULATION_DAE) CHECK(IDASetSuppressAlg(st->mem, SUNTRUE));
  CHECK(IDASetMaxNumSteps(st->mem, 100000000L));
  if (st->settings.max_order >= 1 && st->settings.max_order < 5)
    CHECK(IDASetMaxOrd(st->mem, st->settings.max_order));
  if (st->settings.max_step > 0.0) CHECK(IDASetMaxStep(st->mem, st->settings.max_step));
  CHECK(IDASetInitStep(st->mem, F3R_INITIAL_STEP));
  st->J = SUNDenseMatrix(ny, ny, st->ctx);
  if (!st->J) return f3r_error_set(err, F3R_ERR_MEMORY, "SUNDenseMatrix failed");
  const int kinematic_rows =
      st->settings.formulation == F3R_FORMULATION_MINIMAL ? m->n_independent : m->nq;
  st->ls = uses_schur(&st->settings)
               ? f3r_schur_linsol_create(st->ctx, kinematic_rows, ny, &st->jacobian_cj)
               : SUNLinSol_Dense(y, st->J, st->ctx);
  if (!st->ls) return f3r_error_set(err, F3R_ERR_MEMORY, "linear solver creation failed");
  CHECK(IDASetLinearSolver(st->mem, st->ls, st->J));
  if (st->settings.analytic_jacobian) CHECK(IDASetJacFn(st->mem, jacobian_fn));
  int directions[F3R_NROOTS];
  f3r_stepper_root_directions(directions); /* only moving into a stop or guard */
  CHECK(IDARootInit(st->mem, F3R_NROOTS, root_fn));
  CHECK(IDASetRootDirection(st->mem, directions));
  return F3R_OK;
}

static void ida_stats(const f3r_stepper* st, f3r_sim_stats* out) {
  if (st->ida_counters_folded) { /* nothing counted since the restart; nje, nreDQ are base's */
    *out = st->base;
    out->recoverable_errors = st->recoverable;
    return;
  }
  long nst = 0, nre = 0, nje = 0, netf = 0, nncf = 0, nre_ls = 0;
  realtype hlast = 0.0;
  int kord = 0;
  /* The getters fail only without IDA memory or a linear solver, which a set-up stepper has; a
   * failed one leaves its counter at 0 rather than garbage. */
  if (IDAGetNumSteps(st->mem, &nst) < 0) nst = 0;
  if (IDAGetNumResEvals(st->mem, &nre) < 0) nre = 0;
  if (IDAGetNumJacEvals(st->mem, &nje) < 0) nje = 0;
  if (IDAGetNumLinResEvals(st->mem, &nre_ls) < 0) nre_ls = 0;
  if (IDAGetNumErrTestFails(st->mem, &netf) < 0) netf = 0;
  if (IDAGetNumNonlinSolvConvFails(st->mem, &nncf) < 0) nncf = 0;
  if (IDAGetLastStep(st->mem, &hlast) < 0) hlast = 0.0;
  if (IDAGetLastOrder(st->mem, &kord) < 0) kord = 0;
  *out = st->base;
  out->steps += nst;
  out->residual_evals += nre + nre_ls;
  out->jacobian_evals += nje;
  out->error_test_failures += netf;
  out->nonlinear_failures += nncf;
  out->recoverable_errors = st->recoverable;
  out->last_step = hlast;
  out->last_order = kord;
}

/* IDAReInit zeroes IDA's counters; the linear solver's (nje, nreDQ) are zeroed by the next
 * IDASolve's set-up (idaLsInitialize), and until then ida_stats leaves them out. */
static f3r_status ida_restart(f3r_stepper* st, N_Vector y, N_Vector yp, double t, f3r_error* err) {
  ida_stats(st, &st->base);
  st->ida_counters_folded = 1;
  st->base.restarts++;
  CHECK(IDAReInit(st->mem, t, y, yp));
  CHECK(IDASetInitStep(st->mem, F3R_INITIAL_STEP));
  return F3R_OK;
}

static f3r_status ida_advance(f3r_stepper* st, double tout, double tstop, N_Vector y, N_Vector yp,
                              double* t_reached, int* event, f3r_error* err) {
  /* A stop time outlives a restart in SUNDIALS 6.4 (there is no IDAClearStopTime): always set
   * one, the next breakpoint (or far ahead) when the step may pass tout. */
  const int exact = tstop <= tout;
  CHECK(IDASetStopTime(st->mem, tstop));
  realtype t = *t_reached;
  st->ida_counters_folded = 0;
  const int flag = IDASolve(st->mem, tout, &t, y, yp, IDA_NORMAL);
  *t_reached = t;
  *event = flag == IDA_ROOT_RETURN;
  if (*event) CHECK(IDAGetRootInfo(st->mem, st->root_info));
  if (flag >= 0) return F3R_OK;
  /* Clipped to a stop time, IDA's steps can shrink to where dae's Newton iteration cannot
   * converge (the multipliers amplify roundoff by 1/h^2): seen with dae on paper sim. 3's forcing
   * held every 1 ms, rtol 1e-10, which failed 3e-11 s before the hold at 0.499 s after steps of
   * 3e-10 s. Within one last step of tout, the step's polynomial extrapolated to tout (what IDA's
   * own predictor would start from) is the state there; the solver restarts from it. */
  realtype h_used = 0.0;
  if (exact && flag == IDA_CONV_FAIL && IDAGetLastStep(st->mem, &h_used) >= 0 &&
      tout - t <= fabs(h_used) && IDAGetDky(st->mem, tout, 0, y) >= 0 &&
      IDAGetDky(st->mem, tout, 1, yp) >= 0) {
    *t_reached = tout;
    return ida_restart(st, y, yp, tout, err);
  }
  char message[sizeof st->message];
  snprintf(message, sizeof message, "%s", st->message);
  /* The last successful step is still a good state; IDASolve left y at it already when this
   * interpolation cannot be had. */
  if (IDAGetDky(st->mem, t, 0, y) < 0 || IDAGetDky(st->mem, t, 1, yp) < 0)
    snprintf(message + strlen(message), sizeof message - strlen(message),
             "; the state is IDASolve's own");
  snprintf(st->message, sizeof st->message, "%s", message);
  char* name = IDAGetReturnFlagName(flag); /* allocated by IDA */
  const f3r_status s = f3r_error_set(
      err, flag == IDA_RES_FAIL || flag == IDA_REP_RES_ERR ? F3R_ERR_NONFINITE : F3R_ERR_SOLVER,
      "IDASolve stopped at t = %.9g before %.9g: %s (%s)", t, tout, name ? name : "?", st->message);
  free(name);
  return s;
}

static void ida_release(f3r_stepper* st) {
  if (st->mem) IDAFree(&st->mem);
  if (st->ls) SUNLinSolFree(st->ls);
  if (st->J) SUNMatDestroy(st->J);
  if (st->id) N_VDestroy(st->id);
  if (st->atol) N_VDestroy(st->atol);
  st->ls = NULL;
  st->J = NULL;
  st->id = st->atol = NULL;
}

const f3r_stepper_ops f3r_ida_stepper = {ida_setup, ida_restart, ida_advance, ida_stats,
                                         ida_release};

/* ARKODE ERKStep back end: the minimal formulation as an explicit ODE, integrated by the
 * eighth-order Fehlberg 7(8) pair. SUNDIALS 6.4 has no Verner 8(7) table; its VERNER_8_5_6 is of
 * sixth order and needed 8x more steps here. The undamped elastic modes set the step size, not
 * stiffness, and an eighth-order method resolves oscillations with little numerical damping. */
#include <arkode/arkode_erkstep.h>
#include <stdio.h>

#include "stepper.h"

#define F3R_ERK_DEFAULT_TABLE "ARKODE_FEHLBERG_13_7_8"

static f3r_status failed(f3r_stepper* st, f3r_error* err, const char* call, int flag) {
  return f3r_error_set(err, F3R_ERR_SOLVER, "%s failed: %s (%s)", call,
                       ERKStepGetReturnFlagName(flag), st->message);
}

#define CHECK(call)                                      \
  do {                                                   \
    const int flag_ = (call);                            \
    if (flag_ < 0) return failed(st, err, #call, flag_); \
  } while (0)

static f3r_status erk_setup(f3r_stepper* st, N_Vector y, N_Vector yp, double t0, f3r_error* err) {
  (void)yp;
  st->t_segment = t0;
  if (st->settings.formulation != F3R_FORMULATION_MINIMAL)
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "solver.integrator: erk needs the minimal formulation, not dae");
  st->mem = ERKStepCreate(f3r_stepper_explicit_rhs, t0, y, st->ctx);
  if (!st->mem) return f3r_error_set(err, F3R_ERR_SOLVER, "ERKStepCreate failed");
  CHECK(ERKStepSetErrHandlerFn(st->mem, f3r_stepper_error_handler, st));
  const char* name = st->settings.rk_table[0] ? st->settings.rk_table : F3R_ERK_DEFAULT_TABLE;
  ARKodeButcherTable table = f3r_stepper_load_table(0, name);
  if (!table)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "solver.table: '%s' is not an explicit table",
                         name);
  const int flag = ERKStepSetTable(st->mem, table); /* ERKStep keeps a copy */
  ARKodeButcherTable_Free(table);
  CHECK(flag);
  CHECK(ERKStepSStolerances(st->mem, st->settings.rtol, st->settings.atol));
  CHECK(ERKStepSetUserData(st->mem, st));
  CHECK(ERKStepSetMaxNumSteps(st->mem, 100000000L));
  /* Cubic Hermite output from y and f at both ends of a step, which the stepper has anyway.
   * Degree 5 (ARKODE's default) costs extra right-hand sides at every output: 40 k of 216 k on
   * paper simulation 3 with output every 0.1 ms, for the same digits (rtol 1e-5..1e-9). Where
   * steps are long against the output spacing the output's own error shows: on rigid.yaml (10 ms
   * steps, 1 ms outputs, rtol 1e-7) 3.9 digits with degree 3, 4.3 with degree 5 at 8 right-hand
   * sides per output; stop_at_outputs (the node's) makes every output a step end, exact. */
  CHECK(ERKStepSetInterpolantDegree(st->mem, 3));
  if (st->settings.max_step > 0.0) CHECK(ERKStepSetMaxStep(st->mem, st->settings.max_step));
  int directions[F3R_NROOTS];
  for (int k = 0; k < F3R_NROOTS; ++k) directions[k] = -1;
  CHECK(ERKStepRootInit(st->mem, F3R_NROOTS, f3r_stepper_explicit_roots));
  CHECK(ERKStepSetRootDirection(st->mem, directions));
  return F3R_OK;
}

static void erk_stats(const f3r_stepper* st, f3r_sim_stats* out) {
  long nst = 0, nfe = 0, netf = 0;
  realtype hlast = 0.0;
  /* The getters fail only without ERKStep memory, which a set-up stepper has; a failed one
   * leaves its counter at 0 rather than garbage. */
  if (ERKStepGetNumSteps(st->mem, &nst) < 0) nst = 0;
  if (ERKStepGetNumRhsEvals(st->mem, &nfe) < 0) nfe = 0;
  if (ERKStepGetNumErrTestFails(st->mem, &netf) < 0) netf = 0;
  if (ERKStepGetLastStep(st->mem, &hlast) < 0) hlast = 0.0;
  *out = st->base;
  out->steps += nst;
  out->residual_evals += nfe;
  out->error_test_failures += netf;
  out->recoverable_errors = st->recoverable;
  out->last_step = hlast;
  out->last_order = 8;
}

static f3r_status erk_restart(f3r_stepper* st, N_Vector y, N_Vector yp, double t, f3r_error* err) {
  (void)yp;
  erk_stats(st, &st->base);
  st->base.restarts++;
  CHECK(ERKStepReset(st->mem, t, y));
  st->t_segment = t;
  return F3R_OK;
}

static f3r_status erk_advance(f3r_stepper* st, double tout, double tstop, N_Vector y, N_Vector yp,
                              double* t_reached, int* event, f3r_error* err) {
  CHECK(ERKStepSetStopTime(st->mem, tstop)); /* see stepper_ida.c */
  realtype t = *t_reached;
  const int flag = ERKStepEvolve(st->mem, tout, y, &t, ARK_NORMAL);
  *t_reached = t;
  *event = flag == ARK_ROOT_RETURN;
  if (*event) CHECK(ERKStepGetRootInfo(st->mem, st->root_info));
  (void)yp; /* y' costs a right-hand side: the simulation evaluates it when outputs need it */
  st->yp_stale = 1;
  if (flag >= 0) return F3R_OK;
  /* the last successful step is still a good state; ERKStepEvolve left y there already when
   * this interpolation cannot be had */
  (void)ERKStepGetDky(st->mem, t, 0, y);
  return f3r_error_set(err, flag == ARK_RHSFUNC_FAIL ? F3R_ERR_NONFINITE : F3R_ERR_SOLVER,
                       "ERKStepEvolve stopped at t = %.9g before %.9g: %s (%s)", t, tout,
                       ERKStepGetReturnFlagName(flag), st->message);
}

static void erk_release(f3r_stepper* st) {
  if (st->mem) ERKStepFree(&st->mem);
}

const f3r_stepper_ops f3r_erk_stepper = {erk_setup, erk_restart, erk_advance, erk_stats,
                                         erk_release};

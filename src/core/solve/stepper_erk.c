/* ARKODE ERKStep back end: the minimal formulation as an explicit ODE, integrated by the
 * eighth-order Fehlberg 7(8) pair. SUNDIALS 6.4 has no Verner 8(7) table; its VERNER_8_5_6 is of
 * sixth order and needed 8x more steps here. The undamped elastic modes set the step size, not
 * stiffness, and an eighth-order method resolves oscillations with little numerical damping.
 * What it shares with the DIRK back end (options, restart, advance) is in stepper.c. */
#include <arkode/arkode_erkstep.h>
#include <stdio.h>

#include "stepper.h"

#define F3R_ERK_DEFAULT_TABLE "ARKODE_FEHLBERG_13_7_8"

static void erk_counters(const f3r_stepper* st, f3r_sim_stats* raw);

static const f3r_arkode_calls erk_calls = F3R_ARKODE_CALLS(ERKStep, erk_counters);

static f3r_status erk_setup(f3r_stepper* st, N_Vector y, N_Vector yp, double t0, f3r_error* err) {
  (void)yp;
  ARKodeButcherTable table;
  const f3r_status s = f3r_stepper_explicit_start(st, t0, 0, F3R_ERK_DEFAULT_TABLE, &table, err);
  if (s != F3R_OK) return s;
  st->mem = ERKStepCreate(f3r_stepper_explicit_rhs, t0, y, st->ctx);
  if (!st->mem) {
    ARKodeButcherTable_Free(table);
    return f3r_error_set(err, F3R_ERR_SOLVER, "ERKStepCreate failed");
  }
  const int flag = ERKStepSetTable(st->mem, table); /* ERKStep keeps a copy */
  ARKodeButcherTable_Free(table);
  F3R_STEPPER_CHECK(flag, ERKStepGetReturnFlagName);
  return f3r_arkode_configure(st, &erk_calls, err);
}

static void erk_counters(const f3r_stepper* st, f3r_sim_stats* raw) {
  long nfe = 0;
  if (ERKStepGetNumRhsEvals(st->mem, &nfe) < 0) nfe = 0; /* a failed getter counts 0 */
  f3r_arkode_counters(st, raw);
  raw->residual_evals = nfe;
  raw->last_order = 8;
}

static void erk_release(f3r_stepper* st) {
  if (st->mem) ERKStepFree(&st->mem);
}

const f3r_stepper_ops f3r_erk_stepper = {erk_setup, f3r_arkode_restart, f3r_arkode_advance,
                                         f3r_arkode_stats, erk_release};

/* What the integrator back ends share (stepper.h). */
#include "stepper.h" /* first: it includes stdio.h, which arkode_butcher.h needs */

#include <arkode/arkode_butcher_dirk.h>
#include <arkode/arkode_butcher_erk.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "erk_tables.h"

/* In the order of integrator_kinds.c's table. */
static const f3r_stepper_ops* steppers[F3R_INTEGRATOR_MAX_KINDS] = {
    &f3r_ida_stepper, &f3r_erk_stepper, &f3r_dirk_stepper};

const f3r_stepper_ops* f3r_stepper_ops_of(int kind) {
  return kind >= 0 && kind < f3r_integrator_kind_count() ? steppers[kind] : NULL;
}

f3r_status f3r_integrators_register(const f3r_integrator_kind* kind, const f3r_stepper_ops* ops,
                                    int* index, f3r_error* err) {
  const int k = ops ? f3r_integrator_kind_add(kind) : -1;
  if (k < 0)
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "f3r_integrators_register: '%s' refused (no stepper, a name taken, no "
                         "formulation or %d integrators already)",
                         kind && kind->name ? kind->name : "(null)", F3R_INTEGRATOR_MAX_KINDS);
  steppers[k] = ops;
  *index = k;
  return F3R_OK;
}

void f3r_stepper_error_handler(int code, const char* module, const char* function, char* msg,
                               void* user) {
  f3r_stepper* st = user;
  (void)code;
  snprintf(st->message, sizeof st->message, "%s %s: %s", module, function, msg);
}

int f3r_stepper_roots(const f3r_stepper* st, double t, const double* y, double* g) {
  double force[3] = {0.0, 0.0, 0.0};
  if ((st->locked[0] || st->locked[1] || st->locked[2]) &&
      f3r_stop_forces_at(st->model, st->settings.formulation, f3r_stepper_force_time(st, t), y,
                         st->held, force, st->ws) != F3R_OK)
    return 1;
  return f3r_event_roots(st->model, st->settings.formulation, y, st->locked, force, g);
}

/* SUNDIALS 6.4.1's ERKStep and ARKStep (erkStep_FullRHS, arkStep_FullRHS, ARK_FULLRHS_END) take
 * the last stage's right-hand side for f(t_{n+1}, y_{n+1}), the next step's first stage,
 * whenever |c[s-1] - 1| <= 1e-10 (their TINY). That is f at the step's solution only when the
 * last row of A is b. Fehlberg 7(8), DOP853 and Verner's pairs have c[s-1] = 1 without it, and
 * ran as another, less accurate and less stable method, with s-1 right-hand sides a step
 * (docs/benchmarks/eigenvalues.md). Moving that c 1e-9 below 1 makes ARKODE evaluate the first
 * stage afresh, with this library or any other; the stage's time moves by 1e-9 h. */
static void start_each_step_afresh(ARKodeButcherTable table) {
  if (!table) return;
  const int last = table->stages - 1;
  if (fabs(table->c[last] - 1.0) > 1e-10) return;
  for (int j = 0; j < table->stages; ++j)
    if (fabs(table->A[last][j] - table->b[j]) > 1e-10) {
      table->c[last] = 1.0 - 1e-9;
      return;
    }
}

ARKodeButcherTable f3r_stepper_load_table(int implicit, const char* name) {
  if (!name) return NULL;
  ARKodeButcherTable table = NULL;
  const f3r_erk_table* own = implicit ? NULL : f3r_erk_table_find(name);
  if (implicit)
    table = ARKodeButcherTable_LoadDIRKByName(name);
  else if (!own)
    table = ARKodeButcherTable_LoadERKByName(name);
  else /* ARKODE copies the arrays; it only takes them non-const */
    table = ARKodeButcherTable_Create(own->stages, own->order, own->embedded_order, (double*)own->c,
                                      (double*)own->A, (double*)own->b, (double*)own->b_embedded);
  start_each_step_afresh(table);
  return table;
}

int f3r_stepper_explicit_rhs(realtype t, N_Vector y, N_Vector ydot, void* user) {
  f3r_stepper* st = user;
  st->residual_calls++;
  const f3r_status s =
      f3r_explicit_rhs(st->model, f3r_stepper_force_time(st, t), N_VGetArrayPointer(y), st->held,
                       N_VGetArrayPointer(ydot), st->ws);
  if (s == F3R_OK) return 0;
  st->recoverable++;
  return 1; /* recoverable: ARKODE retries with a smaller step */
}

int f3r_stepper_explicit_roots(realtype t, N_Vector y, realtype* g, void* user) {
  return f3r_stepper_roots(user, t, N_VGetArrayPointer(y), g);
}

f3r_status f3r_stepper_failed(const f3r_stepper* st, f3r_error* err, const char* call,
                              char* flag_name) {
  const f3r_status s = f3r_error_set(err, F3R_ERR_SOLVER, "%s failed: %s (%s)", call,
                                     flag_name ? flag_name : "?", st->message);
  free(flag_name);
  return s;
}

void f3r_stepper_root_directions(int directions[F3R_NROOTS]) {
  for (int k = 0; k < F3R_NROOTS; ++k) directions[k] = -1;
}

f3r_status f3r_stepper_explicit_start(f3r_stepper* st, double t0, int implicit,
                                      const char* default_table, ARKodeButcherTable* table,
                                      f3r_error* err) {
  const char* integrator = f3r_integrator_name(st->settings.integrator);
  *table = NULL;
  st->t_segment = t0;
  if (st->settings.formulation != F3R_FORMULATION_MINIMAL)
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "solver.integrator: %s needs the minimal formulation, not dae",
                         integrator);
  const char* name = st->settings.rk_table[0] ? st->settings.rk_table : default_table;
  *table = f3r_stepper_load_table(implicit, name);
  if (!*table)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "solver.table: '%s' is not %s table", name,
                         implicit ? "a diagonally implicit" : "an explicit");
  return F3R_OK;
}

f3r_status f3r_arkode_configure(f3r_stepper* st, const f3r_arkode_calls* calls, f3r_error* err) {
#define CHECK(call) F3R_STEPPER_CHECK(call, calls->flag_name)
  st->arkode = calls;
  CHECK(calls->set_err_handler(st->mem, f3r_stepper_error_handler, st));
  CHECK(calls->ss_tolerances(st->mem, st->settings.rtol, st->settings.atol));
  CHECK(calls->set_user_data(st->mem, st));
  CHECK(calls->set_max_num_steps(st->mem, 100000000L));
  /* Quartic Hermite output: y and f at both ends of the step and one more right-hand side inside
   * it, at each of ARKODE's two interpolations per output (the root check at tout, then y(tout)).
   * Measured against stop-at-outputs references (docs/solvers.md, "Outputs between steps"):
   * cubic loses up to a digit where steps are long against the outputs (rigid.yaml, rtol 1e-9,
   * 1 ms outputs: 1.6e-7 m cubic, 5.9e-8 m quartic; paper simulation 3 at 0.1 ms outputs,
   * rtol 1e-5: energy balance 6.4e-7 J cubic, 2.8e-8 J quartic, for 3 % more CPU). Quintic
   * (ARKODE's default) is no better in any of them and costs four right-hand sides an
   * interpolation; stop_at_outputs (the node's) makes every output a step end. */
  CHECK(calls->set_interpolant_degree(st->mem, 4));
  st->step_cap = st->settings.max_step > 0.0 ? st->settings.max_step : 0.0;
  if (st->step_cap > 0.0) CHECK(calls->set_max_step(st->mem, st->step_cap));
  int directions[F3R_NROOTS];
  f3r_stepper_root_directions(directions);
  CHECK(calls->root_init(st->mem, F3R_NROOTS, f3r_stepper_explicit_roots));
  CHECK(calls->set_root_direction(st->mem, directions));
  return F3R_OK;
}

/* ARKODE's Reset keeps its counters (SUNDIALS 6.4.1): ERKStepReset and ARKStepReset call
 * arkInit with RESET_INIT, which zeroes nst and netf only for FIRST_INIT, and the steppers' init
 * returns at once on a reset, so the linear and nonlinear solvers' counts (nje, nls_fails) stay
 * too; nfe and nfi are zeroed only by Create and ReInit. So base takes only what was counted since
 * the last restart, and the counters are read again after the reset: before the first step a
 * reset is a FIRST_INIT, which zeroes some. */
static f3r_status restart_with_step(f3r_stepper* st, N_Vector y, double t, double step_scale,
                                    f3r_error* err) {
  const f3r_arkode_calls* calls = st->arkode;
  f3r_arkode_stats(st, &st->base);
  calls->counters(st, &st->counted); /* in base now, also if the reset fails */
  st->base.restarts++;
  realtype last = 0.0;
  if (calls->get_last_step(st->mem, &last) < 0) last = 0.0;
  CHECK(calls->reset(st->mem, t, y));
  /* The step the run had reached, not a fresh estimate: from a quiet state the estimate took
   * 0.13 s at once after a held force stepped, into a pose the legs cannot reach, and ERKStep
   * (SUNDIALS 6.4.1) does not recover from a right-hand side that asks for a smaller step. */
  if (last > 0.0) CHECK(calls->set_init_step(st->mem, last * step_scale));
  calls->counters(st, &st->counted);
  st->t_segment = t;
  return F3R_OK;
}

f3r_status f3r_arkode_restart(f3r_stepper* st, N_Vector y, N_Vector yp, double t, f3r_error* err) {
  (void)yp;
  return restart_with_step(st, y, t, 1.0, err);
}

/* ERKStep (SUNDIALS 6.4.1, erkStep_TakeStep) gives up when the right-hand side asks for a smaller
 * step, which it does for a stage in a state it cannot evaluate. After a breakpoint the restart
 * takes the step the run had reached, which a quiet segment before it may have made long: on
 * table_pulses_fixed_free (2 modes + the pair a link) every table stopped 2 ms after the first
 * pulse. Made again from its start with a hundredth of that step, every table ran it through. */
#define F3R_RETRIES_AFTER_A_REFUSED_STAGE 3

int f3r_arkode_retry_refused(f3r_stepper* st, long asked_before, int* retries, N_Vector start,
                             N_Vector y, double t, f3r_error* err) {
  if (!st->arkode || st->recoverable == asked_before ||
      *retries >= F3R_RETRIES_AFTER_A_REFUSED_STAGE)
    return 0;
  ++*retries;
  N_VScale(1.0, start, y);
  return restart_with_step(st, y, t, 1e-2, err) == F3R_OK;
}

f3r_status f3r_arkode_advance(f3r_stepper* st, double tout, double tstop, N_Vector y, N_Vector yp,
                              double* t_reached, int* event, f3r_error* err) {
  (void)yp; /* y' costs a right-hand side: the simulation evaluates it when outputs need it */
  const f3r_arkode_calls* calls = st->arkode;
  CHECK(calls->set_stop_time(st->mem, tstop)); /* see stepper_ida.c */
  /* The quartic Hermite output errs as the step's fifth power, the method's steps only as their
   * eighth on Fehlberg 7(8): on rigid.yaml at rtol 1e-9, 1 ms outputs, steps of up to 46 ms put
   * the outputs between them 5.3e-7 m off, where their ends are within 1e-16 m. Capped at four
   * output intervals: 79 steps instead of 28, 5.3e-11 m (eight: 48, 1.8e-9 m; docs/solvers.md).
   * Elastic links' steps are far shorter than such a cap. */
  if (!st->settings.stop_at_outputs && st->output_interval > 0.0) {
    double cap = 4.0 * st->output_interval;
    if (st->settings.max_step > 0.0) cap = fmin(cap, st->settings.max_step);
    if (cap != st->step_cap) CHECK(calls->set_max_step(st->mem, cap));
    st->step_cap = cap;
  }
  realtype t = *t_reached;
  const int flag = calls->evolve(st->mem, tout, y, &t, ARK_NORMAL);
  *t_reached = t;
  *event = flag == ARK_ROOT_RETURN;
  if (*event) CHECK(calls->get_root_info(st->mem, st->root_info));
  st->yp_stale = 1;
  if (flag >= 0) return F3R_OK;
  /* the last successful step is still a good state; Evolve left y there already when this
   * interpolation cannot be had */
  (void)calls->get_dky(st->mem, t, 0, y);
  char* name = calls->flag_name(flag);
  const f3r_status s =
      f3r_error_set(err, flag == ARK_RHSFUNC_FAIL ? F3R_ERR_NONFINITE : F3R_ERR_SOLVER,
                    "%s stopped at t = %.9g before %.9g: %s (%s)", calls->evolve_name, t, tout,
                    name ? name : "?", st->message);
  free(name);
  return s;
#undef CHECK
}

void f3r_arkode_counters(const f3r_stepper* st, f3r_sim_stats* raw) {
  const f3r_arkode_calls* calls = st->arkode;
  long steps = 0, fails = 0;
  realtype last = 0.0;
  if (calls->get_num_steps(st->mem, &steps) < 0) steps = 0;
  if (calls->get_num_err_test_fails(st->mem, &fails) < 0) fails = 0;
  if (calls->get_last_step(st->mem, &last) < 0) last = 0.0;
  *raw = (f3r_sim_stats){0};
  raw->steps = steps;
  raw->error_test_failures = fails;
  raw->last_step = last;
}

/* base plus the counts since the last restart (f3r_arkode_restart) */
void f3r_arkode_stats(const f3r_stepper* st, f3r_sim_stats* out) {
  f3r_sim_stats now;
  st->arkode->counters(st, &now);
  const f3r_sim_stats* then = &st->counted;
  *out = st->base;
  out->steps += now.steps - then->steps;
  out->residual_evals += now.residual_evals - then->residual_evals;
  out->jacobian_evals += now.jacobian_evals - then->jacobian_evals;
  out->error_test_failures += now.error_test_failures - then->error_test_failures;
  out->nonlinear_failures += now.nonlinear_failures - then->nonlinear_failures;
  out->recoverable_errors = st->recoverable;
  out->last_step = now.last_step;
  out->last_order = now.last_order;
}

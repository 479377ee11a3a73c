/* The accuracy knob's pilot (accuracy_parts.h): short nonlinear runs that check the linear mode
 * estimate, exact kinematics and the chosen solver, carried to the whole run. Runs once before a
 * simulation, so it allocates freely. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accuracy_parts.h"

/* The nonlinear end-effector path at t_k = k dt, k < count, with the given solver: a pilot. */
static f3r_status pilot_path(const f3r_scene* base, const int modes[3], int exact_kinematics,
                             const f3r_solver_settings* solver, double dt, int count, double* pose,
                             f3r_error* err) {
  f3r_model* model = NULL;
  f3r_sim* sim = NULL;
  f3r_status st = f3r_model_with_modes(base, modes, exact_kinematics, &model, err);
  if (st == F3R_OK) st = f3r_sim_create(model, solver, &sim, err);
  /* The pose straight from the state (the minimal formulation's z starts with it, the dae's q
   * holds it at F3R_Q_X): the full outputs' forward pass and multipliers would cost a pilot a
   * tenth of its time. */
  const int pose_at =
      solver->formulation == F3R_FORMULATION_MINIMAL ? F3R_Q_X - F3R_Q_INDEPENDENT : F3R_Q_X;
  for (int k = 0; st == F3R_OK && k < count; ++k) {
    if (k) st = f3r_sim_advance(sim, k * dt, err);
    const double* y = f3r_sim_state(sim);
    for (int c = 0; c < 3; ++c) pose[3 * k + c] = y[pose_at + c];
  }
  f3r_sim_destroy(sim);
  f3r_model_destroy(model);
  if (st != F3R_OK) {
    char why[sizeof err->message] = "failed"; /* a copy: the message is rewritten from itself */
    if (err) snprintf(why, sizeof why, "%s", err->message);
    return f3r_error_set(err, st, "accuracy: pilot run at %d, %d, %d modes: %s", modes[0], modes[1],
                         modes[2], why);
  }
  return F3R_OK;
}

/* The relation of the loosest minimal IDA whose measured error stays below `error`, NULL if none
 * (the pilot then takes the baseline rtol 1e-6, with `error` as its noise). capped: never looser
 * than that baseline, for a run longer than the benchmark's scenes, where the relations can be
 * short. */
static const f3r_solver_relation* pilot_relation(const char* kind, double error, int capped) {
  const f3r_solver_relation* best = NULL;
  for (int k = 0; k < f3r_solver_relation_count; ++k) {
    const f3r_solver_relation* r = &f3r_solver_relations[k];
    if (!strcmp(r->kind, kind) && r->formulation == F3R_FORMULATION_MINIMAL &&
        r->integrator == F3R_INTEGRATOR_IDA && r->error <= error &&
        (!best || r->rtol > best->rtol) && (!capped || r->rtol <= 1e-6 * (1.0 + 1e-9)))
      best = r;
  }
  return best;
}

double f3r_pilot_cost(const char* kind, double resolution, int capped) {
  const f3r_solver_relation* r = pilot_relation(kind, resolution, capped);
  return r ? r->cost
           : 1.0; /* the baseline, minimal IDA at 1e-6, is what the costs are measured from */
}

void f3r_pilot_free(f3r_pilot* p) { /* safe twice: the knob drops a pilot of the other basis */
  free(p->a);
  free(p->b);
  p->a = p->b = NULL;
}

/* A difference over the window carried to the whole run: d(W) T / W. A difference that starts at
 * t = 0 grows as t^2 at first, whatever it does later, so the window cannot tell its later growth;
 * linear growth is what a phase error gives, and what paper simulation 3's nonlinear differences
 * show over the whole run (their ratio to the linear ones, 2.7 at 0.05 s, 5 at 0.1 s, 23 at 0.5 s). */
static double extrapolate(const f3r_pilot* p, const double* x, const double* y) {
  return f3r_max_distance(x, y, p->count) * fmax(p->grow, 1.0);
}

f3r_status f3r_pilot_start(const f3r_scene* s, const f3r_mode_search* ms, const int modes[3],
                           int exact_kinematics, const char* kind, double resolution, int capped,
                           f3r_pilot* p, f3r_error* err) {
  memset(p, 0, sizeof *p);
  const double window = fmax(F3R_PILOT_SHARE * s->duration, ms->dt);
  p->count =
      ms->count < (int)ceil(window / ms->dt) + 1 ? ms->count : (int)ceil(window / ms->dt) + 1;
  p->grow = s->duration / ((p->count - 1) * ms->dt);
  p->tight = f3r_solver_settings_from_scene(s);
  p->tight.formulation = F3R_FORMULATION_MINIMAL;
  p->tight.integrator = F3R_INTEGRATOR_IDA;
  const f3r_solver_relation* r = pilot_relation(kind, resolution, capped);
  p->tight.rtol = r ? r->rtol : 1e-6;
  p->noise = r ? r->error : resolution;
  p->tight.atol = fmin(1e-2 * p->tight.rtol, s->atol); /* positions resolved from the start */
  p->tight.rk_table[0] = '\0';
  memcpy(p->modes, modes, sizeof p->modes);
  p->exact_kinematics = exact_kinematics;
  p->a = malloc((size_t)p->count * 3 * sizeof(double));
  p->b = malloc((size_t)p->count * 3 * sizeof(double));
  if (!p->a || !p->b) return f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  return pilot_path(s, modes, exact_kinematics, &p->tight, ms->dt, p->count, p->a, err);
}

/* The nonlinear difference of r and r + 1 modes, carried to the whole run (0 within the pilot's
 * noise), and the linear difference of the same pair over the whole run. */
f3r_status f3r_pilot_pair(const f3r_scene* s, f3r_mode_search* ms, f3r_pilot* p, double* nonlinear,
                          double* linear, f3r_error* err) {
  *nonlinear = *linear = 0.0;
  int more[3];
  for (int i = 0; i < 3; ++i)
    more[i] = (ms->chosen >> i & 1) && p->modes[i] < ms->most[i] ? p->modes[i] + 1 : p->modes[i];
  double* la = malloc((size_t)ms->count * 3 * sizeof(double));
  double* lb = malloc((size_t)ms->count * 3 * sizeof(double));
  f3r_status st = la && lb ? F3R_OK : f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  if (st == F3R_OK &&
      (st = pilot_path(s, more, p->exact_kinematics, &p->tight, ms->dt, p->count, p->b, err)) ==
          F3R_OK &&
      (st = f3r_mode_search_path(s, ms, p->modes, 1, la, err)) == F3R_OK &&
      (st = f3r_mode_search_path(s, ms, more, 1, lb, err)) == F3R_OK) {
    *linear = f3r_max_distance(la, lb, ms->count);
    /* Below three times the pilot's own solver error the difference says nothing. */
    if (f3r_max_distance(p->a, p->b, p->count) > 3.0 * p->noise)
      *nonlinear = extrapolate(p, p->a, p->b);
  }
  free(la), free(lb);
  return st;
}

/* The effect of turning exact kinematics on at the pilot's modes, carried to the whole run. Not
 * gated by the pilot's noise: both runs take the same solver and nearly the same steps, so their
 * difference holds little of it, and an effect below the noise can still exceed the kinematics'
 * share. */
f3r_status f3r_pilot_kinematics(const f3r_scene* s, const f3r_mode_search* ms, f3r_pilot* p,
                                double* effect, f3r_error* err) {
  *effect = 0.0;
  const f3r_status st = pilot_path(s, p->modes, 1, &p->tight, ms->dt, p->count, p->b, err);
  if (st == F3R_OK) *effect = extrapolate(p, p->a, p->b);
  return st;
}

/* The error of a solver at the pilot's modes against the tight pilot, carried to the whole run (0
 * when within the pilot's own noise). */
f3r_status f3r_pilot_solver(const f3r_scene* s, const f3r_mode_search* ms, f3r_pilot* p,
                            const f3r_solver_settings* solver, double* error, f3r_error* err) {
  *error = 0.0;
  const f3r_status st =
      pilot_path(s, p->modes, p->exact_kinematics, solver, ms->dt, p->count, p->b, err);
  if (st == F3R_OK && f3r_max_distance(p->a, p->b, p->count) > 3.0 * p->noise)
    *error = extrapolate(p, p->a, p->b);
  return st;
}

/* The measured solver relations (solver_table.c) as costs and budgets: which solver a request
 * leaves room for, at what cost, for the knob (accuracy.c) and its basis comparison
 * (accuracy_basis.c). */
#include <math.h>
#include <string.h>

#include "accuracy_parts.h"
#include "flex3rpr/kinds.h"

/* A relation's cost, an explicit integrator's scaled by explicit_scale. */
double f3r_relation_cost(const f3r_solver_relation* r, double explicit_scale) {
  const f3r_integrator_kind* kind = f3r_integrator_kind_at((int)r->integrator);
  return kind && kind->explicit_method ? r->cost * explicit_scale : r->cost;
}

/* The cheapest measured solver whose error fits `budget`, among those the scene leaves open, with
 * explicit integrators' cost scaled by `explicit_scale`. */
const f3r_solver_relation* f3r_pick_solver(const f3r_scene* s, const char* kind, double budget,
                                           double explicit_scale) {
  const f3r_solver_relation* best = NULL;
  double best_cost = 0.0;
  const unsigned fixed = s->explicit_settings;
  for (int k = 0; k < f3r_solver_relation_count; ++k) {
    const f3r_solver_relation* r = &f3r_solver_relations[k];
    if (strcmp(r->kind, kind) || r->error > budget) continue;
    if ((fixed & F3R_EXPLICIT_FORMULATION) && r->formulation != s->formulation) continue;
    if ((fixed & F3R_EXPLICIT_INTEGRATOR) && r->integrator != s->integrator) continue;
    if ((fixed & F3R_EXPLICIT_RTOL) && r->rtol != s->rtol) continue;
    if ((fixed & F3R_EXPLICIT_TABLE) && strcmp(r->table, s->table)) continue;
    const double cost = f3r_relation_cost(r, explicit_scale);
    if (!best || cost < best_cost || (cost == best_cost && r->rtol > best->rtol)) {
      best = r;
      best_cost = cost;
    }
  }
  return best;
}

/* Explicit integrators' cost scale at these mode counts: a step's right-hand side grows with the
 * modes beyond the benchmark's, and so does an explicit method's step count. */
double f3r_explicit_scale_of(const int modes[3]) {
  int most = 0;
  for (int i = 0; i < 3; ++i) most = modes[i] > most ? modes[i] : most;
  return most > BENCHMARK_MODES ? (double)(most * most) / (BENCHMARK_MODES * BENCHMARK_MODES) : 1.0;
}

/* The relative cost of the solver a basis leaves room for: the cheapest measured relation within
 * the request less the basis's model error and the kinematics' (at least the solver's share), a
 * tenth of that on the static correction (pick_relation keeps it there); 1, minimal IDA at rtol
 * 1e-6, where the scene sets its solver or none fits. The bases' costs are compared with it: on
 * resonance_damped at 1e-5 m they tie (3 modes, 1 mode + shapes), and the correction's tighter
 * solver made it 1.6 times the CPU time (docs/benchmarks/accuracy_knob.md). */
/* The solver's budget: what the request leaves beside the model's and the kinematics' errors,
 * at least the solver's share of it where the model keeps to its own share (past it, the model's
 * error was let in only with room left for a solver: f3r_choice_wide_model_target). */
double f3r_choice_solver_budget(const choice_run* run, const f3r_accuracy_choice* c,
                                double model_error) {
  const double left = run->request - model_error - c->kinematics_error;
  if (model_error > run->model_target) return left;
  return fmax(left, F3R_ACCURACY_SOLVER_SHARE * run->request);
}

double f3r_choice_wide_model_target(const choice_run* run, const f3r_accuracy_choice* c) {
  if (!run->solver_open) return 0.0;
  double least = INFINITY; /* the smallest measured error of a solver the scene leaves open */
  for (double budget = run->request; budget > 0.0; budget = least * 0.5) {
    const f3r_solver_relation* r = f3r_pick_solver(run->scene, run->kind, budget, 1.0);
    if (!r || !(r->error < least)) break;
    least = r->error;
  }
  return run->request - c->kinematics_error - least / SOLVER_CHECK_SHARE;
}

double f3r_choice_solver_cost(const choice_run* run, const f3r_accuracy_choice* c,
                              const int modes[3], double model_error, int corrected) {
  if (!run->solver_open) return 1.0;
  double budget = f3r_choice_solver_budget(run, c, model_error);
  if (corrected) budget *= SOLVER_CHECK_SHARE;
  const double scale = f3r_explicit_scale_of(modes);
  const f3r_solver_relation* r = f3r_pick_solver(run->scene, run->kind, budget, scale);
  return r ? f3r_relation_cost(r, scale) : 1.0;
}

/* The measured error of the scene's own fixed solver (the nearest tolerance at or below). */
double f3r_solver_error_of(const f3r_scene* s, const char* kind) {
  double error = NAN, at = 0.0;
  for (int k = 0; k < f3r_solver_relation_count; ++k) {
    const f3r_solver_relation* r = &f3r_solver_relations[k];
    if (strcmp(r->kind, kind) || r->formulation != s->formulation ||
        r->integrator != s->integrator ||
        strcmp(r->table, s->explicit_settings & F3R_EXPLICIT_TABLE ? s->table : "") ||
        r->rtol > s->rtol * (1.0 + 1e-9))
      continue;
    if (r->rtol > at) {
      at = r->rtol;
      error = r->error;
    }
  }
  return error;
}

/* What the scene leaves open (links' mode counts, exact kinematics, the solver) and which
 * solver relations apply to it; s becomes the working copy, a view sharing scene's tables. */

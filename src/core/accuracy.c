/* The accuracy knob (include/flex3rpr/accuracy.h): chooses mode counts (accuracy_search.c),
 * checks them, exact kinematics and the solver with a pilot (accuracy_pilot.c), and picks the
 * measured solver relation. Runs once before a simulation, so it allocates freely; nothing here
 * touches the step loop. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accuracy_parts.h"

/* s: the longest of the work-precision benchmark's scenes (paper simulation 3), over which the
 * solver relations of solver_table.c were measured */
#define BENCHMARK_DURATION 0.5

/* The cheapest measured solver whose error fits `budget`, among those the scene leaves open. */
static const f3r_solver_relation* pick_solver(const f3r_scene* s, const char* kind, double budget) {
  const f3r_solver_relation* best = NULL;
  const unsigned fixed = s->explicit_settings;
  for (int k = 0; k < f3r_solver_relation_count; ++k) {
    const f3r_solver_relation* r = &f3r_solver_relations[k];
    if (strcmp(r->kind, kind) || r->error > budget) continue;
    if ((fixed & F3R_EXPLICIT_FORMULATION) && r->formulation != s->formulation) continue;
    if ((fixed & F3R_EXPLICIT_INTEGRATOR) && r->integrator != s->integrator) continue;
    if ((fixed & F3R_EXPLICIT_RTOL) && r->rtol != s->rtol) continue;
    if ((fixed & F3R_EXPLICIT_TABLE) && strcmp(r->table, s->table)) continue;
    if (!best || r->cost < best->cost || (r->cost == best->cost && r->rtol > best->rtol)) best = r;
  }
  return best;
}

/* The measured error of the scene's own fixed solver (the nearest tolerance at or below). */
static double solver_error_of(const f3r_scene* s, const char* kind) {
  double error = NAN, at = 0.0;
  for (int k = 0; k < f3r_solver_relation_count; ++k) {
    const f3r_solver_relation* r = &f3r_solver_relations[k];
    if (strcmp(r->kind, kind) || r->formulation != s->formulation || r->integrator != s->integrator ||
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

static const char* integrator_name(f3r_integrator i) {
  return i == F3R_INTEGRATOR_ERK ? "erk" : i == F3R_INTEGRATOR_DIRK ? "dirk" : "ida";
}

static void append(char* text, size_t size, const char* fmt, ...) __attribute__((format(printf, 3, 4)));
static void append(char* text, size_t size, const char* fmt, ...) {
  const size_t used = strlen(text);
  if (used + 1 >= size) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(text + used, size - used, fmt, ap);
  va_end(ap);
}

f3r_status f3r_accuracy_choose(const f3r_scene* scene, double request, int commanded,
                               f3r_accuracy_choice* c, f3r_error* err) {
  memset(c, 0, sizeof *c);
  if (!(request > 0.0) || !isfinite(request))
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "accuracy: the request must be a positive length (m)");
  c->request = request;
  unsigned chosen = 0;
  int any_flexible = 0;
  f3r_scene s = *scene;
  for (int i = 0; i < 3; ++i) {
    if (!f3r_is_flexible(scene, i)) continue;
    any_flexible = 1;
    if (!(scene->explicit_settings & (F3R_EXPLICIT_MODES << i))) {
      chosen |= 1u << i;
      s.links[i].modes = 1; /* a placeholder until chosen */
    }
  }
  const char* kind = commanded && any_flexible ? "commanded" : any_flexible ? "flexible" : "rigid";
  const double model_target = F3R_ACCURACY_MODEL_SHARE * request;
  const int kinematics_open = any_flexible && !(scene->explicit_settings & F3R_EXPLICIT_EXACT_KINEMATICS);
  f3r_mode_search ms;
  f3r_status st = f3r_mode_search_init(&s, chosen, &ms, err);
  double linear_error = 0.0;
  if (st == F3R_OK) st = f3r_mode_search_run(&s, &ms, model_target, c->modes, &linear_error, err);
  c->extent = ms.extent;
  c->model_error = linear_error;
  c->pilot_ratio = 1.0;
  c->exact_kinematics = scene->exact_kinematics;
  f3r_pilot pilot = {0};
  const unsigned solver_fixed = F3R_EXPLICIT_FORMULATION | F3R_EXPLICIT_INTEGRATOR | F3R_EXPLICIT_RTOL;
  const int solver_open = (scene->explicit_settings & solver_fixed) != solver_fixed;
  if (st == F3R_OK && ms.far && (chosen || kinematics_open || solver_open)) {
    st = f3r_pilot_start(&s, &ms, c->modes, kind, 0.1 * model_target, &pilot, err);
    c->pilot = st == F3R_OK;
    /* The nonlinear difference of r and r + 1, times the linear model's tail beyond r + 1 (its
     * r-against-reference over r-against-r + 1, within 1..10), bounds the model error from
     * below; where it exceeds the linear estimate, the estimate is short by their ratio for
     * every r, and the search runs again with the target shrunk by it. */
    double nonlinear = 0.0, linear = 0.0;
    if (st == F3R_OK && chosen) st = f3r_pilot_pair(&s, &ms, &pilot, &nonlinear, &linear, err);
    const double tail = linear > 0.0 ? fmin(fmax(linear_error / linear, 1.0), 10.0) : 1.0;
    if (getenv("F3R_ACCURACY_DEBUG"))
      fprintf(stderr, "pilot: nonlinear %g linear %g linear_error %g tail %g noise %g rtol %g\n", nonlinear,
              linear, linear_error, tail, pilot.noise, pilot.tight.rtol);
    const double estimate = fmax(linear_error, nonlinear * tail);
    if (st == F3R_OK && estimate > linear_error) {
      c->pilot_ratio = linear_error > 0.0 ? estimate / linear_error : INFINITY;
      c->model_error = estimate;
      if (estimate > model_target && isfinite(c->pilot_ratio)) {
        st = f3r_mode_search_run(&s, &ms, model_target / c->pilot_ratio, c->modes, &linear_error, err);
        c->model_error = c->pilot_ratio * linear_error;
      }
    }
    if (st == F3R_OK && kinematics_open) {
      st = f3r_pilot_kinematics(&s, &ms, &pilot, &c->kinematics_effect, err);
      c->exact_kinematics = c->kinematics_effect > F3R_ACCURACY_KINEMATICS_SHARE * request;
      c->kinematics_error = c->exact_kinematics ? 0.0 : c->kinematics_effect;
    }
  }
  /* A run longer than the benchmark's scenes drifts further than their relations say (a phase
   * error grows with time): a pilot then measures the chosen solver on this scene as well. */
  int solver_pilot = 0;
  if (st == F3R_OK && !c->pilot && solver_open && !ms.at_rest && s.duration > BENCHMARK_DURATION) {
    st = f3r_pilot_start(&s, &ms, c->modes, kind, 0.1 * model_target, &pilot, err);
    solver_pilot = st == F3R_OK;
  }
  const int measured_solver = c->pilot || solver_pilot;
  c->linear_evaluations = ms.evaluations;
  const int rest = ms.at_rest, order = ms.order, reference = ms.ref_r;
  if (st != F3R_OK) {
    f3r_pilot_free(&pilot);
    f3r_mode_search_free(&ms);
    return st;
  }

  char* text = c->summary;
  const size_t size = sizeof c->summary;
  append(text, size, "accuracy %g m on the end-effector path (shares: model %g, kinematics %g, solver %g)\n",
         request, F3R_ACCURACY_MODEL_SHARE, F3R_ACCURACY_KINEMATICS_SHARE, F3R_ACCURACY_SOLVER_SHARE);
  for (int i = 0; i < 3; ++i) {
    if (!f3r_is_flexible(scene, i)) append(text, size, "links[%d]: rigid\n", i);
    else if (!(chosen >> i & 1)) append(text, size, "links[%d]: %d modes, as the scene sets\n", i, c->modes[i]);
    else append(text, size, "links[%d]: %d modes\n", i, c->modes[i]);
  }
  if (chosen && rest)
    append(text, size, "modes: nothing excites the scene (no inputs, initial rates or deflections)\n");
  else if (chosen)
    append(text, size,
           "modes: the %s-order linearised path is within %.3g m of the same with %d modes (path "
           "extent %.3g m, %d linear models)\n",
           order == 2 ? "second" : "first", linear_error, reference, c->extent, c->linear_evaluations);
  if (c->pilot)
    append(text, size,
           "pilot: the path leaves the initial pose (%.3g m); nonlinear runs over the first %.0f%% of it, "
           "carried to the whole, scale the linear estimate by %.3g\n",
           c->extent, 100.0 * F3R_PILOT_SHARE, c->pilot_ratio);
  if (!any_flexible) append(text, size, "exact kinematics: no flexible link\n");
  else if (!kinematics_open)
    append(text, size, "exact kinematics: %s, as the scene sets\n", c->exact_kinematics ? "on" : "off");
  else if (!c->pilot)
    append(text, size, "exact kinematics: off (second order in the deflections; the path stays near the initial pose)\n");
  else
    append(text, size, "exact kinematics: %s (its effect is estimated at %.3g m; the limit is %.3g m)\n",
           c->exact_kinematics ? "on" : "off", c->kinematics_effect,
           F3R_ACCURACY_KINEMATICS_SHARE * request);

  double budget = request - c->model_error - c->kinematics_error;
  budget = fmax(budget, F3R_ACCURACY_SOLVER_SHARE * request);
  c->formulation = scene->formulation;
  c->integrator = scene->integrator;
  c->rtol = scene->rtol;
  c->atol = scene->atol;
  snprintf(c->table, sizeof c->table, "%s", scene->table);
  if (!solver_open) {
    c->solver_error = solver_error_of(scene, kind);
    append(text, size, "solver: %s, %s, rtol %g, as the scene sets (measured error %.3g m)\n",
           scene->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal",
           integrator_name(scene->integrator), scene->rtol, c->solver_error);
  } else {
    /* The cheapest measured relation within the budget; where a pilot ran, its own error there
     * checks the relation, and a relation it exceeds is replaced by one the excess allows. */
    double limit = budget, measured = 0.0;
    const f3r_solver_relation* r = NULL;
    for (int attempt = 0; attempt < 3; ++attempt) {
      const f3r_solver_relation* next = pick_solver(scene, kind, limit);
      if (!next || next == r) break;
      r = next;
      if (!measured_solver) break;
      f3r_scene trial = s;
      trial.formulation = r->formulation;
      trial.integrator = r->integrator;
      trial.rtol = r->rtol;
      trial.atol = scene->explicit_settings & F3R_EXPLICIT_ATOL ? scene->atol : r->atol;
      snprintf(trial.table, sizeof trial.table, "%s", r->table);
      const f3r_solver_settings settings = f3r_solver_settings_from_scene(&trial);
      if ((st = f3r_pilot_solver(&s, &ms, &pilot, &settings, &measured, err)) != F3R_OK) break;
      if (measured <= budget) break;
      limit = r->error * budget / measured; /* the relation is short by measured / error here */
    }
    if (st != F3R_OK) {
      f3r_pilot_free(&pilot);
      f3r_mode_search_free(&ms);
      return st;
    }
    if (!r) {
      c->solver_error = solver_error_of(scene, kind);
      append(text, size, "solver: no measured solver fits %.3g m; keeping %s, rtol %g\n", budget,
             integrator_name(scene->integrator), scene->rtol);
    } else {
      c->formulation = r->formulation;
      c->integrator = r->integrator;
      c->rtol = r->rtol;
      if (!(scene->explicit_settings & F3R_EXPLICIT_ATOL)) c->atol = r->atol;
      snprintf(c->table, sizeof c->table, "%s", r->table);
      c->solver_error = fmax(r->error, measured);
      append(text, size,
             "solver: %s, %s%s%s, rtol %g, atol %g: the cheapest measured within %.3g m (at most %.3g m on "
             "the %d %s benchmark scenes; cost %.2g of minimal IDA at 1e-6; measured on %s)\n",
             r->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal",
             integrator_name(r->integrator), r->table[0] ? " " : "", r->table, r->rtol, c->atol, budget,
             r->error, r->scenes, r->kind, r->cost, f3r_solver_relations_source);
      if (solver_pilot)
        append(text, size,
               "solver: the run is longer than the benchmark's scenes (%g s); a pilot over its first "
               "%.0f%% measures %.3g m for it over the run\n",
               BENCHMARK_DURATION, 100.0 * F3R_PILOT_SHARE, measured);
      else if (c->pilot)
        append(text, size, "solver: the pilot measures %.3g m for it over the run\n", measured);
    }
  }
  f3r_pilot_free(&pilot);
  f3r_mode_search_free(&ms);
  const double total = c->model_error + c->kinematics_error + (isfinite(c->solver_error) ? c->solver_error : 0.0);
  /* Neither the linear model nor a pilot window sees an impact's jump, and a path with impacts
   * need not converge in the mode count at all: end_stop_impact at 12 and 20 modes (exact
   * kinematics, rtol 1e-9 and 1e-11) part by 5 cm within 0.3 s. Say so rather than promise. */
  const int impacts = s.end_stops && !rest;
  if (impacts)
    append(text, size, "end stops: impacts are outside this estimate (with them the path need not converge in "
                       "the mode count); check the result against a run with more modes\n");
  append(text, size, "estimated error %.3g m (model %.3g, kinematics %.3g, solver %.3g)", total,
         c->model_error, c->kinematics_error, c->solver_error);
  char how[64] = "linear estimate";
  if (c->pilot) snprintf(how, sizeof how, "linear estimate x %.3g from the pilot", c->pilot_ratio);
  snprintf(c->brief, sizeof c->brief,
           "accuracy %g m: modes %d/%d/%d (%s), exact kinematics %s, %s %s%s%s rtol %g; "
           "estimated %.3g m%s",
           request, c->modes[0], c->modes[1], c->modes[2], how, c->exact_kinematics ? "on" : "off",
           c->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal", integrator_name(c->integrator),
           c->table[0] ? " " : "", c->table, c->rtol, total, impacts ? " without the impacts" : "");
  return F3R_OK;
}

void f3r_accuracy_apply(const f3r_accuracy_choice* c, f3r_scene* s) {
  for (int i = 0; i < 3; ++i)
    if (f3r_is_flexible(s, i)) s->links[i].modes = c->modes[i];
  s->exact_kinematics = c->exact_kinematics;
  s->formulation = c->formulation;
  s->integrator = c->integrator;
  s->rtol = c->rtol;
  s->atol = c->atol;
  snprintf(s->table, sizeof s->table, "%s", c->table);
}

f3r_status f3r_accuracy_resolve(f3r_scene* scene, int commanded, f3r_accuracy_choice* choice,
                                f3r_error* err) {
  f3r_accuracy_choice local;
  f3r_accuracy_choice* c = choice ? choice : &local;
  memset(c, 0, sizeof *c);
  if (scene->accuracy > 0.0) {
    const f3r_status st = f3r_accuracy_choose(scene, scene->accuracy, commanded, c, err);
    if (st == F3R_OK) f3r_accuracy_apply(c, scene);
    return st;
  }
  unsigned chosen = 0;
  double tolerance = 0.0;
  for (int i = 0; i < 3; ++i)
    if (f3r_is_flexible(scene, i) && scene->links[i].modes == F3R_MODES_AUTO) {
      chosen |= 1u << i;
      tolerance = fmax(tolerance, scene->links[i].auto_tolerance);
    }
  if (!chosen) return F3R_OK;
  f3r_scene s = *scene;
  for (int i = 0; i < 3; ++i)
    if (chosen >> i & 1) s.links[i].modes = 1;
  const f3r_status st = f3r_accuracy_modes(&s, chosen, -tolerance, c->modes, &c->model_error,
                                           &c->extent, &c->linear_evaluations, err);
  if (st != F3R_OK) return st;
  snprintf(c->brief, sizeof c->brief,
           "modes auto: %d/%d/%d (linearised path within %.3g m of 3r + 3 modes, auto_tolerance %g "
           "of its extent %.3g m)",
           c->modes[0], c->modes[1], c->modes[2], c->model_error, tolerance, c->extent);
  for (int i = 0; i < 3; ++i) {
    if (chosen >> i & 1) scene->links[i].modes = c->modes[i];
    if (chosen >> i & 1)
      append(c->summary, sizeof c->summary,
             "links[%d]: modes auto -> %d (linearised path within %.3g m of 3r + 3 modes: "
             "auto_tolerance %g of its extent %.3g m)\n",
             i, c->modes[i], c->model_error, tolerance, c->extent);
  }
  return F3R_OK;
}

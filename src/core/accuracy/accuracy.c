/* The accuracy knob (include/flex3rpr/accuracy.h): chooses mode counts (accuracy_search.c),
 * checks them and the solver with a pilot (accuracy_pilot.c), and picks the measured solver
 * relation; exact kinematics is on unless the scene turns it off, and then its effect is counted.
 * Runs once before a simulation, so it allocates freely; nothing here touches the step loop. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accuracy_parts.h"

/* s: the longest of the work-precision benchmark's scenes (paper simulation 3), over which the
 * solver relations of solver_table.c were measured */
#define BENCHMARK_DURATION 0.5
/* The largest ratio of the nonlinear to the linear mode-count difference the pilot measured on the
 * shipped scenes is 30 (paper simulation 3, fixed-free links); a linear estimate this many times
 * below the model's share is left unchecked, as no such ratio lifts it there. */
#define PAIR_SKIP_FACTOR 100.0
/* The largest ratio of exact kinematics' effect in the pilot to its linear estimate
 * (f3r_linear_kinematics) on the shipped scenes is 23 (free_vibration_long; paper simulation 3
 * with fixed-free links 16, payload_pick 10, all others below 3.2 at the pilot's tightest
 * tolerance); where a scene turns exact kinematics off, a linear estimate this many times below
 * the kinematics' share is taken as its effect unchecked. */
#define KINEMATICS_SKIP_FACTOR 100.0
/* A measured relation whose error is within this share of the solver's budget is left unchecked
 * on a run no longer than the benchmark's scenes. */
#define SOLVER_CHECK_SHARE 0.1
/* Impacts amplify the solver's error far beyond the relations: on end_stop_impact, 20 modes with
 * exact kinematics at rtol 1e-5 land 7.2e-3 m from the reference, where the relation says
 * 1.75e-7 m (4e4 times); at rtol 1e-6, 2.3e-3 m against 2.55e-8 (9e4 times); at rtol 1e-7,
 * 7.0e-6 m against 4.6e-9 (1.5e3 times). */
#define IMPACT_AMPLIFICATION 1e5

/* The relations were measured with 3 modes a flexible link (the paper's scenes). An explicit
 * integrator's step is bound by the highest mode, whose frequency grows as r^2 for a beam; an
 * implicit one's is not. */
#define BENCHMARK_MODES 3

/* A relation's cost, an explicit integrator's scaled by explicit_scale. */
static double relation_cost(const f3r_solver_relation* r, double explicit_scale) {
  return r->integrator == F3R_INTEGRATOR_ERK ? r->cost * explicit_scale : r->cost;
}

/* The cheapest measured solver whose error fits `budget`, among those the scene leaves open, with
 * explicit integrators' cost scaled by `explicit_scale`. */
static const f3r_solver_relation* pick_solver(const f3r_scene* s, const char* kind, double budget,
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
    const double cost = relation_cost(r, explicit_scale);
    if (!best || cost < best_cost || (cost == best_cost && r->rtol > best->rtol)) {
      best = r;
      best_cost = cost;
    }
  }
  return best;
}

/* The measured error of the scene's own fixed solver (the nearest tolerance at or below). */
static double solver_error_of(const f3r_scene* s, const char* kind) {
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

static const char* integrator_name(f3r_integrator i) {
  return i == F3R_INTEGRATOR_ERK ? "erk" : i == F3R_INTEGRATOR_DIRK ? "dirk" : "ida";
}

static void append(char* text, size_t size, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void append(char* text, size_t size, const char* fmt, ...) {
  const size_t used = strlen(text);
  if (used + 1 >= size) return;
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(text + used, size - used, fmt, ap);
  va_end(ap);
}

/* Why a choice's estimate exceeds its request: the largest part, and what holds it there. */
static void unmet_reason(const f3r_scene* scene, const f3r_accuracy_choice* c, unsigned chosen,
                         int solver_open, char* why, size_t size) {
  const double solver = isfinite(c->solver_error) ? c->solver_error : 0.0;
  if (c->model_error >= c->kinematics_error && c->model_error >= solver) {
    int fixed = 0, at_most = 0;
    for (int i = 0; i < 3; ++i) {
      if (!f3r_is_flexible(scene, i)) continue;
      if (!(chosen >> i & 1))
        fixed = 1;
      else if (c->modes[i] >= F3R_MAX_MODES)
        at_most = 1;
    }
    snprintf(why, size, "the largest part is the model's (%.3g m): %s", c->model_error,
             fixed     ? "the scene sets mode counts"
             : at_most ? "the mode counts are at their most"
                       : "as the pilot scales it");
  } else if (c->kinematics_error >= solver) {
    snprintf(why, size,
             "the largest part is exact kinematics' effect (%.3g m): the scene turns it off",
             c->kinematics_error);
  } else {
    const unsigned set = scene->explicit_settings;
    char fixed[64] = "";
    if (set & F3R_EXPLICIT_FORMULATION) append(fixed, sizeof fixed, " formulation");
    if (set & F3R_EXPLICIT_INTEGRATOR) append(fixed, sizeof fixed, " integrator");
    if (set & F3R_EXPLICIT_RTOL) append(fixed, sizeof fixed, " rtol");
    if (set & F3R_EXPLICIT_TABLE) append(fixed, sizeof fixed, " table");
    if (!solver_open)
      snprintf(why, size, "the largest part is the solver's (%.3g m): the scene sets the solver",
               solver);
    else if (fixed[0])
      snprintf(why, size, "the largest part is the solver's (%.3g m): the scene sets its%s", solver,
               fixed);
    else
      snprintf(why, size,
               "the largest part is the solver's (%.3g m): no measured solver reaches the budget "
               "on this run",
               solver);
  }
}

/* What the stages of one choice share: the scene and its working copy (the chosen links' modes
 * a placeholder), what the scene leaves open, the mode search and the pilot (freed at the end),
 * and the facts the summary reports. */
typedef struct {
  const f3r_scene* scene; /* the caller's */
  const f3r_scene* s;     /* the working copy */
  double request;
  double model_target; /* m: the model's share of the request */
  const char* kind;    /* the solver relations' kind: rigid, flexible or commanded */
  unsigned chosen;     /* the links whose mode counts the knob chooses */
  int any_flexible;
  int kinematics_open, kinematics_off, solver_open;
  f3r_mode_search ms;
  int impacts;            /* end stops on a path that moves: the most faithful model */
  int long_run;           /* longer than the benchmark's scenes */
  double linear_error;    /* m: the search's last linear estimate */
  int pair, pair_skipped; /* the pilot's pair ran, or was skipped as needless */
  int kinematics;         /* a pilot measures exact kinematics' effect */
  int kinematics_linear_only;
  f3r_pilot pilot;
  int pilot_started;
} choice_run;

/* The solver relation being checked: the budget, the current limit on the relation's error,
 * and what the pilot measured. */
typedef struct {
  double budget, limit, measured;
  int checked;
  const f3r_solver_relation* relation;
  const f3r_solver_relation*
      skipped_check; /* the cheapest one, whose check cost more than it saves */
} solver_pick;

/* What the scene leaves open (links' mode counts, exact kinematics, the solver) and which
 * solver relations apply to it; s becomes the working copy. */
static void open_choice(const f3r_scene* scene, double request, int commanded, f3r_scene* s,
                        choice_run* run) {
  *run = (choice_run){.scene = scene, .s = s, .request = request};
  f3r_scene_copy(s, scene);
  for (int i = 0; i < 3; ++i) {
    if (!f3r_is_flexible(scene, i)) continue;
    run->any_flexible = 1;
    if (!(scene->explicit_settings & (F3R_EXPLICIT_MODES << i))) {
      run->chosen |= 1u << i;
      s->links[i].modes = 1; /* a placeholder until chosen */
    }
  }
  run->kind = commanded && run->any_flexible ? "commanded"
              : run->any_flexible            ? "flexible"
                                             : "rigid";
  run->model_target = F3R_ACCURACY_MODEL_SHARE * request;
  /* Exact kinematics costs no measurable CPU time: runs with it on take 0.86 to 1.05 times the
   * steps of the same runs without it and, within the machine's noise, the same time (median 0.98
   * to 1.01 in three runs of scripts/bench_accuracy: 39 pairs each, every shipped scene with a
   * flexible link at r = 1 and 3, minimal and dae on IDA; 0.89 to 1.11, median 0.98, over 15 more
   * pairs up to r = 20 and with both ERK tables, medians of 7 to 15 runs in turns). So it is on
   * wherever the scene leaves it open: its part of the error goes to 0 at no cost, where an
   * estimate (a linear response, or a pilot run of a tenth of the duration) could only have
   * turned it off to save nothing. Where the scene turns it off, its effect is estimated. */
  run->kinematics_open =
      run->any_flexible && !(scene->explicit_settings & F3R_EXPLICIT_EXACT_KINEMATICS);
  run->kinematics_off = run->any_flexible && !run->kinematics_open && !scene->exact_kinematics;
  const unsigned solver_fixed =
      F3R_EXPLICIT_FORMULATION | F3R_EXPLICIT_INTEGRATOR | F3R_EXPLICIT_RTOL;
  run->solver_open = (scene->explicit_settings & solver_fixed) != solver_fixed;
}

/* The mode counts: the fewest whose linearised path stays within the model's share, or the most
 * faithful model where there are impacts. */
static f3r_status search_modes(choice_run* run, f3r_accuracy_choice* c, f3r_error* err) {
  const f3r_mode_search* ms = &run->ms;
  f3r_status st = f3r_mode_search_init(run->s, run->chosen, &run->ms, err);
  run->impacts = st == F3R_OK && run->s->end_stops && !ms->at_rest;
  /* A run longer than the benchmark's scenes drifts further than their relations say (a phase
   * error grows with time): a pilot then measures the chosen solver on this scene as well. */
  run->long_run = st == F3R_OK && !ms->at_rest && run->s->duration > BENCHMARK_DURATION;
  c->pilot_ratio = 1.0;
  c->exact_kinematics = run->kinematics_open ? 1 : run->scene->exact_kinematics;
  if (st == F3R_OK && run->impacts) {
    /* Neither the linear model nor a pilot window sees an impact's jump, and a path with impacts
     * need not converge in the mode count at all (end_stop_impact: 12 and 20 modes part by 5 cm
     * within 0.3 s): the knob takes the most faithful model, with no estimate of its error. */
    for (int i = 0; i < 3; ++i) c->modes[i] = (ms->chosen >> i & 1) ? F3R_MAX_MODES : ms->fixed[i];
  } else if (st == F3R_OK) {
    st =
        f3r_mode_search_run(run->s, &run->ms, run->model_target, c->modes, &run->linear_error, err);
  }
  c->extent = ms->extent;
  c->model_error = run->linear_error;
  return st;
}

/* The pilot at the least mode counts: the pair's nonlinear difference scales the linear estimate
 * (and the search runs again where that lifts it over the model's share), and a run without
 * exact kinematics measures its effect. */
static f3r_status run_mode_pilot(choice_run* run, f3r_accuracy_choice* c, f3r_error* err) {
  int least[3];
  f3r_mode_search_least(&run->ms, least);
  f3r_status st = f3r_pilot_start(run->s, &run->ms, least, c->exact_kinematics, run->kind,
                                  0.1 * run->model_target, run->long_run, &run->pilot, err);
  run->pilot_started = 1;
  c->pilot = st == F3R_OK;
  /* The nonlinear difference of the least mode counts and one more, over the linear one of the
   * same pair: where it exceeds 1, the linear estimate is short by that ratio for every r (the
   * least counts, where the differences stand far above the pilot's noise, say it best), and
   * the search runs again with the target shrunk by it. */
  double nonlinear = 0.0, linear = 0.0;
  if (st == F3R_OK && run->pair)
    st = f3r_pilot_pair(run->s, &run->ms, &run->pilot, &nonlinear, &linear, err);
  const double ratio = linear > 0.0 ? nonlinear / linear : 1.0;
  if (st == F3R_OK && ratio > 1.0) {
    c->pilot_ratio = ratio;
    c->model_error = ratio * run->linear_error;
    if (c->model_error > run->model_target) {
      st = f3r_mode_search_run(run->s, &run->ms, run->model_target / ratio, c->modes,
                               &run->linear_error, err);
      c->model_error = ratio * run->linear_error;
    }
  }
  if (st == F3R_OK && run->kinematics) {
    st = f3r_pilot_kinematics(run->s, &run->ms, &run->pilot, &c->kinematics_effect, err);
    c->kinematics_error = c->kinematics_effect;
  }
  return st;
}

/* Where the path leaves the initial pose far, what the linear estimate cannot see is checked: the
 * modes by a pair of nonlinear pilot runs, exact kinematics' effect (where the scene turns it
 * off) by its linear estimate or a pilot. */
static f3r_status check_modes(choice_run* run, f3r_accuracy_choice* c, f3r_error* err) {
  f3r_status st = F3R_OK;
  /* The pair of nonlinear runs checks the linear estimate unless that estimate is so far below the
   * model's share that no measured ratio could lift it there. */
  const int far = !run->impacts && run->ms.far;
  run->pair = far && run->chosen && PAIR_SKIP_FACTOR * run->linear_error > run->model_target;
  run->pair_skipped = far && run->chosen && !run->pair;
  run->kinematics = far && run->kinematics_off;
  if (run->kinematics && !run->pair) {
    /* Exact kinematics' effect to first order, where it may spare the pilot (a pair of pilots runs
     * anyway otherwise, and a third costs about what the estimate does): a pilot measures it
     * unless it is far below its share. */
    int least[3];
    f3r_mode_search_least(&run->ms, least);
    st = f3r_linear_kinematics(run->s, &run->ms, least, &c->kinematics_linear, err);
    if (KINEMATICS_SKIP_FACTOR * c->kinematics_linear <=
        F3R_ACCURACY_KINEMATICS_SHARE * run->request) {
      run->kinematics = 0;
      c->kinematics_effect = c->kinematics_error = c->kinematics_linear;
    }
  }
  run->kinematics_linear_only = far && run->kinematics_off && !run->kinematics;
  if (st == F3R_OK && (run->pair || run->kinematics)) st = run_mode_pilot(run, c, err);
  return st;
}

/* The summary's lines on the request, the mode counts and the pilot that checked them. */
static void summarise_modes(const choice_run* run, f3r_accuracy_choice* c) {
  char* text = c->summary;
  const size_t size = sizeof c->summary;
  const f3r_mode_search* ms = &run->ms;
  append(text, size,
         "accuracy %g m on the end-effector path (shares: model %g, kinematics %g, solver %g)\n",
         run->request, F3R_ACCURACY_MODEL_SHARE, F3R_ACCURACY_KINEMATICS_SHARE,
         F3R_ACCURACY_SOLVER_SHARE);
  for (int i = 0; i < 3; ++i) {
    if (!f3r_is_flexible(run->scene, i))
      append(text, size, "links[%d]: rigid\n", i);
    else if (!(run->chosen >> i & 1))
      append(text, size, "links[%d]: %d modes, as the scene sets\n", i, c->modes[i]);
    else
      append(text, size, "links[%d]: %d modes\n", i, c->modes[i]);
  }
  if (run->chosen && run->impacts)
    append(text, size,
           "modes: end stops: impacts are outside the linear estimate, and the path need not "
           "converge in the mode count; the most faithful model (%d modes)\n",
           F3R_MAX_MODES);
  else if (run->chosen && ms->at_rest)
    append(text, size,
           "modes: nothing excites the scene (no inputs, initial rates or deflections)\n");
  else if (run->chosen)
    append(text, size,
           "modes: the %s-order linearised path is within %.3g m of the same with %d modes (path "
           "extent %.3g m, %d linear models)\n",
           ms->order == 2 ? "second" : "first", run->linear_error, ms->ref_r, c->extent,
           c->linear_evaluations);
  if (c->pilot && run->pair)
    append(text, size,
           "pilot: the path leaves the initial pose (%.3g m); nonlinear runs at the least mode "
           "counts over "
           "the first %.0f%% of it, carried to the whole, scale the linear estimate by %.3g\n",
           c->extent, 100.0 * F3R_PILOT_SHARE, c->pilot_ratio);
  else if (run->pair_skipped)
    append(text, size,
           "pilot: the path leaves the initial pose (%.3g m), but its linear estimate is below "
           "1/%g of the "
           "model's share, beyond any nonlinear ratio measured; not checked\n",
           c->extent, PAIR_SKIP_FACTOR);
}

/* The summary's line on exact kinematics: on, or off as the scene sets and how its effect is
 * counted. */
static void summarise_kinematics(const choice_run* run, f3r_accuracy_choice* c) {
  char* text = c->summary;
  const size_t size = sizeof c->summary;
  if (!run->any_flexible)
    append(text, size, "exact kinematics: no flexible link\n");
  else if (run->kinematics_open && run->impacts)
    append(text, size, "exact kinematics: on (the most faithful model)\n");
  else if (run->kinematics_open)
    append(
        text, size,
        "exact kinematics: on: it costs no measurable CPU time (the same steps and time as "
        "without it on the shipped scenes), so its part of the error is removed, not estimated\n");
  else if (!run->kinematics_off)
    append(text, size, "exact kinematics: on, as the scene sets\n");
  else if (run->kinematics_linear_only)
    append(text, size,
           "exact kinematics: off, as the scene sets; its linear estimate %.3g m, below 1/%g of "
           "its share "
           "%.3g m (beyond any ratio a pilot measured), is counted unchecked\n",
           c->kinematics_linear, KINEMATICS_SKIP_FACTOR,
           F3R_ACCURACY_KINEMATICS_SHARE * run->request);
  else if (!run->kinematics)
    append(
        text, size,
        "exact kinematics: off, as the scene sets; its effect is second order in the deflections "
        "and the path stays near the initial pose: not estimated\n");
  else {
    char linear[64] = "";
    if (c->kinematics_linear > 0.0)
      snprintf(linear, sizeof linear, ", its linear estimate %.3g m", c->kinematics_linear);
    append(text, size,
           "exact kinematics: off, as the scene sets; a pilot estimates its effect at %.3g m%s, "
           "counted in the estimate\n",
           c->kinematics_effect, linear);
  }
}

/* The solver settings of relation r for a pilot's check, on the working copy's other settings. */
static f3r_solver_settings relation_settings(const choice_run* run, const f3r_solver_relation* r) {
  f3r_solver_settings settings = f3r_solver_settings_from_scene(run->s);
  settings.formulation = r->formulation;
  settings.integrator = r->integrator;
  settings.rtol = r->rtol;
  settings.atol = run->scene->explicit_settings & F3R_EXPLICIT_ATOL ? run->scene->atol : r->atol;
  snprintf(settings.rk_table, sizeof settings.rk_table, "%s", r->table);
  return settings;
}

/* The cheapest measured relation within the budget (with impacts, within the budget over their
 * amplification). A run longer than the benchmark's scenes, or a far one whose relation comes
 * near the budget, has the relation checked by a pilot at the chosen modes; a relation the
 * pilot finds short is replaced by one the excess allows. */
static f3r_status pick_relation(choice_run* run, const f3r_accuracy_choice* c, solver_pick* p,
                                f3r_error* err) {
  const f3r_scene* scene = run->scene;
  const double budget = p->budget;
  f3r_status st = F3R_OK;
  p->limit = run->impacts ? budget / IMPACT_AMPLIFICATION : budget;
  int most = 0;
  for (int i = 0; i < 3; ++i) most = c->modes[i] > most ? c->modes[i] : most;
  const double explicit_scale =
      most > BENCHMARK_MODES ? (double)(most * most) / (BENCHMARK_MODES * BENCHMARK_MODES) : 1.0;
  for (int attempt = 0; attempt < 4; ++attempt) {
    const f3r_solver_relation* next = pick_solver(scene, run->kind, p->limit, explicit_scale);
    if (!next || next == p->relation) break;
    const f3r_solver_relation* r = p->relation = next;
    /* once a relation fell short here, its successors are checked too */
    if (run->impacts ||
        !(run->long_run || p->checked || (run->ms.far && r->error > SOLVER_CHECK_SHARE * budget)))
      break;
    if (!run->long_run && !p->checked) {
      /* A check runs a pilot window at the relation, after the tight pilot's when none ran yet;
       * the cheapest relation that needs no check may cost less than that over the run. */
      const double check = F3R_PILOT_SHARE *
                           (relation_cost(r, explicit_scale) +
                            (run->pilot_started ? 0.0
                                                : f3r_pilot_cost(run->kind, 0.1 * run->model_target,
                                                                 run->long_run)));
      const f3r_solver_relation* safe =
          pick_solver(scene, run->kind, SOLVER_CHECK_SHARE * budget, explicit_scale);
      if (safe && relation_cost(safe, explicit_scale) <= relation_cost(r, explicit_scale) + check) {
        p->skipped_check = r;
        p->relation = safe;
        p->limit = SOLVER_CHECK_SHARE * budget;
        break;
      }
    }
    if (!run->pilot_started) {
      st = f3r_pilot_start(run->s, &run->ms, c->modes, c->exact_kinematics, run->kind,
                           0.1 * run->model_target, run->long_run, &run->pilot, err);
      run->pilot_started = 1;
      if (st != F3R_OK) break;
    }
    const f3r_solver_settings settings = relation_settings(run, r);
    /* At the pilot's least modes where it ran already: the relation, measured at each benchmark
     * scene's own modes, checked on this scene's motion at a fraction of the cost. */
    if ((st = f3r_pilot_solver(run->s, &run->ms, &run->pilot, &settings, &p->measured, err)) !=
        F3R_OK)
      break;
    p->checked = 1;
    if (p->measured <= budget) break;
    /* The relation is short by measured / error here; a decade at a most per attempt, as the
     * pilot's least modes can make it look shorter than it is at the chosen ones. */
    p->limit = fmax(r->error * budget / p->measured, 0.1 * r->error);
  }
  return st;
}

/* The summary's lines on the relation taken: where it was measured, and how it was checked. */
static void summarise_relation(const choice_run* run, f3r_accuracy_choice* c,
                               const solver_pick* p) {
  char* text = c->summary;
  const size_t size = sizeof c->summary;
  const f3r_solver_relation* r = p->relation;
  append(text, size,
         "solver: %s, %s%s%s, rtol %g, atol %g: the cheapest measured within %.3g m (at most %.3g "
         "m on "
         "the %d %s benchmark scenes; cost %.2g of minimal IDA at 1e-6; measured on %s)\n",
         r->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal", integrator_name(r->integrator),
         r->table[0] ? " " : "", r->table, r->rtol, c->atol, p->limit, r->error, r->scenes, r->kind,
         r->cost, f3r_solver_relations_source);
  if (run->impacts)
    append(text, size,
           "solver: impacts amplify the solver's error (up to %g times on end_stop_impact); "
           "the budget %.3g m is divided by that\n",
           IMPACT_AMPLIFICATION, p->budget);
  else if (p->checked && run->long_run)
    append(text, size,
           "solver: the run is longer than the benchmark's scenes (%g s); a pilot over its first "
           "%.0f%% measures %.3g m for it over the run\n",
           BENCHMARK_DURATION, 100.0 * F3R_PILOT_SHARE, p->measured);
  else if (p->checked)
    append(text, size, "solver: the pilot measures %.3g m for it over the run\n", p->measured);
  else if (p->skipped_check)
    append(text, size,
           "solver: rtol %g, the cheapest within the budget, would need a pilot's check that "
           "costs more than this one does over it; this one's measured error is below %g of "
           "the budget: not checked\n",
           p->skipped_check->rtol, SOLVER_CHECK_SHARE);
  else if (run->ms.far)
    append(text, size, "solver: its measured error is below %g of the budget; not checked\n",
           SOLVER_CHECK_SHARE);
}

/* The solver: the scene's own where it sets one, else the cheapest measured relation within the
 * budget the model and exact kinematics leave, kept unless none fits. */
static f3r_status choose_solver(choice_run* run, f3r_accuracy_choice* c, f3r_error* err) {
  const f3r_scene* scene = run->scene;
  solver_pick p = {0};
  p.budget = run->request - c->model_error - c->kinematics_error;
  p.budget = fmax(p.budget, F3R_ACCURACY_SOLVER_SHARE * run->request);
  c->formulation = scene->formulation;
  c->integrator = scene->integrator;
  c->rtol = scene->rtol;
  c->atol = scene->atol;
  snprintf(c->table, sizeof c->table, "%s", scene->table);
  if (!run->solver_open) {
    c->solver_error = solver_error_of(scene, run->kind);
    append(c->summary, sizeof c->summary,
           "solver: %s, %s, rtol %g, as the scene sets (measured error %.3g m)\n",
           scene->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal",
           integrator_name(scene->integrator), scene->rtol, c->solver_error);
    return F3R_OK;
  }
  const f3r_status st = pick_relation(run, c, &p, err);
  if (st != F3R_OK) return st;
  const f3r_solver_relation* r = p.relation;
  if (!r) {
    c->solver_error = solver_error_of(scene, run->kind);
    append(c->summary, sizeof c->summary,
           "solver: no measured solver fits %.3g m; keeping %s, rtol %g\n", p.limit,
           integrator_name(scene->integrator), scene->rtol);
    return F3R_OK;
  }
  c->formulation = r->formulation;
  c->integrator = r->integrator;
  c->rtol = r->rtol;
  if (!(scene->explicit_settings & F3R_EXPLICIT_ATOL)) c->atol = r->atol;
  snprintf(c->table, sizeof c->table, "%s", r->table);
  c->solver_error = fmax(r->error, p.measured);
  summarise_relation(run, c, &p);
  return F3R_OK;
}

/* The estimate's total, whether it meets the request (and what holds it where it does not), and
 * the one-line brief. */
static void summarise_estimate(const choice_run* run, f3r_accuracy_choice* c) {
  const double request = run->request;
  const double total =
      c->model_error + c->kinematics_error + (isfinite(c->solver_error) ? c->solver_error : 0.0);
  c->estimated_error = total;
  c->request_met = total <= request;
  append(
      c->summary, sizeof c->summary,
      "estimated error %.3g m (model %.3g, kinematics %.3g, solver %.3g)%s", total, c->model_error,
      c->kinematics_error, c->solver_error,
      run->impacts
          ? "; the impacts' effect on the model is not estimated: check the result against a run "
            "with other modes"
          : "");
  if (!c->request_met) {
    char why[160];
    unmet_reason(run->scene, c, run->chosen, run->solver_open, why, sizeof why);
    append(c->summary, sizeof c->summary, "\nnot met: the estimate is %.3g times the request; %s",
           total / request, why);
  }
  char how[64] = "linear estimate";
  if (run->impacts)
    snprintf(how, sizeof how, "the most faithful: impacts");
  else if (c->pilot)
    snprintf(how, sizeof how, "linear estimate x %.3g from the pilot", c->pilot_ratio);
  snprintf(c->brief, sizeof c->brief,
           "accuracy %g m: modes %d/%d/%d (%s), exact kinematics %s, %s %s%s%s rtol %g; "
           "estimated %.3g m%s",
           request, c->modes[0], c->modes[1], c->modes[2], how, c->exact_kinematics ? "on" : "off",
           c->formulation == F3R_FORMULATION_DAE ? "dae" : "minimal",
           integrator_name(c->integrator), c->table[0] ? " " : "", c->table, c->rtol, total,
           run->impacts ? " without the impacts" : "");
  if (!c->request_met)
    append(c->brief, sizeof c->brief, "; NOT MET (%.3g x the request)", total / request);
}

/* The stages in order: what is open, the mode counts and their check, the summary of both, the
 * solver, then the estimate. */
f3r_status f3r_accuracy_choose(const f3r_scene* scene, double request, int commanded,
                               f3r_accuracy_choice* c, f3r_error* err) {
  memset(c, 0, sizeof *c);
  if (!(request > 0.0) || !isfinite(request))
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "accuracy: the request must be a positive length (m)");
  c->request = request;
  f3r_scene s;
  choice_run run;
  open_choice(scene, request, commanded, &s, &run);
  f3r_status st = search_modes(&run, c, err);
  if (st == F3R_OK) st = check_modes(&run, c, err);
  c->linear_evaluations = run.ms.evaluations;
  if (st == F3R_OK) {
    summarise_modes(&run, c);
    summarise_kinematics(&run, c);
    st = choose_solver(&run, c, err);
  }
  f3r_pilot_free(&run.pilot);
  f3r_mode_search_free(&run.ms);
  if (st == F3R_OK) summarise_estimate(&run, c);
  return st;
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
  f3r_scene s;
  f3r_scene_copy(&s, scene);
  for (int i = 0; i < 3; ++i)
    if (chosen >> i & 1) s.links[i].modes = 1;
  const f3r_status st = f3r_accuracy_modes(&s, chosen, -tolerance, c->modes, &c->model_error,
                                           &c->extent, &c->linear_evaluations, err);
  if (st != F3R_OK) return st;
  c->estimated_error = c->model_error;
  c->request_met = 1; /* no request: auto_tolerance, of the path's extent, decides */
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

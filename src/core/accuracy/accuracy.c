/* The accuracy knob (include/flex3rpr/accuracy.h): chooses mode counts (accuracy_search.c),
 * compares the paper's modes with the static correction (accuracy_basis.c), checks them and the
 * solver with a pilot (accuracy_pilot.c), and picks the measured solver relation (their costs:
 * accuracy_solver.c); exact kinematics is on unless the scene turns it off, and then its effect is counted.
 * Runs once before a simulation, so it allocates freely; nothing here touches the step loop. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accuracy_parts.h"

/* Commands from outside are unknown when the knob chooses: it sizes the model for steps of
 * accuracy.excitation (limits.force unless the scene states less) on the leg forces at t = 0,
 * alternating in sign so that they move and turn the platform, on every leg the scene scripts
 * nothing for. A scene at rest would otherwise say that nothing excites it, and choose the
 * least model for any controller. The closed-loop measurement (session.h) then says whether
 * the commands that came were within it. */
static double add_command_excitation(f3r_scene* s) {
  const double size = s->accuracy_excitation > 0.0 ? s->accuracy_excitation : s->limit_force;
  int added = 0;
  for (int i = 0; i < 3; ++i) {
    f3r_input* in = &s->inputs[F3R_FORCE_RHO + i];
    if (in->kind != F3R_INPUT_NONE) continue;
    *in = (f3r_input){
        .kind = F3R_INPUT_STEP, .t0 = 0.0, .before = 0.0, .after = i == 1 ? -size : size};
    added = 1;
  }
  return added ? size : 0.0;
}

static void open_choice(const f3r_scene* scene, double request, int commanded, f3r_scene* s,
                        choice_run* run) {
  *run = (choice_run){.scene = scene, .s = s, .request = request};
  *s = *scene;
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
  if (commanded && run->any_flexible) run->excitation = add_command_excitation(s);
  run->model_target = F3R_ACCURACY_MODEL_SHARE * request;
  /* Exact kinematics costs no measurable CPU time: runs with it on take 0.86 to 1.05 times the
   * steps of the same runs without it and, within the machine's noise, the same time (median 0.98
   * to 1.01 in three runs of bench/accuracy_knob: 39 pairs each, every shipped scene with a
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
  f3r_status st = f3r_mode_search_init(run->s, run->chosen, NULL, &run->ms, err);
  run->impacts = st == F3R_OK && run->s->end_stops && !ms->at_rest;
  /* A run longer than the benchmark's scenes drifts further than their relations say (a phase
   * error grows with time): a pilot then measures the chosen solver on this scene as well. */
  run->long_run = st == F3R_OK && !ms->at_rest && run->s->duration > BENCHMARK_DURATION;
  c->pilot_ratio = 1.0;
  c->exact_kinematics = run->kinematics_open ? 1 : run->scene->exact_kinematics;
  if (st == F3R_OK && run->impacts) {
    /* A path with impacts need not converge in the mode count at all (an impact's impulse
     * excites every mode: end_stop_impact's 12 and 20 modes part by 5 cm within 0.3 s), so no
     * model is faithful past the first impact and the most faithful one only costs more (a 0.5 s
     * scene with 281 impacts ran for minutes). The knob sizes the model for the path the linear
     * model sees, between impacts; the measured run then says whether the path converges
     * (docs/accuracy.md). */
    st =
        f3r_mode_search_run(run->s, &run->ms, run->model_target, c->modes, &run->linear_error, err);
  } else if (st == F3R_OK && f3r_choice_plain_search_may_wait(run)) {
    /* Beyond its first part the search waits for the corrected one (compare_correction), the
     * least counts standing in until then. Far from the pose that part runs now, and where it
     * fits the whole search does (from the memo): its estimate may then spare the pilot's pair
     * (check_modes), which otherwise runs. Paper simulation 3 with fixed-free links at 1e-5 m:
     * the search at r = 3 .. 20 it spares took 3 of the choosing's 12 ms. */
    int fits = 0;
    if (ms->far) st = f3r_choice_plain_first_part(run, run->model_target, &fits, err);
    if (st == F3R_OK && fits) {
      st = f3r_mode_search_run(run->s, &run->ms, run->model_target, c->modes, &run->linear_error,
                               err);
    } else if (st == F3R_OK) {
      run->deferred_target = run->model_target;
      f3r_mode_search_least(ms, c->modes);
    }
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
  if (st == F3R_OK && ratio > 1.0 && run->deferred_target > 0.0) {
    c->pilot_ratio = ratio; /* the search, when it runs, runs within the target shrunk by it */
    run->deferred_target = run->model_target / ratio;
  } else if (st == F3R_OK && ratio > 1.0) {
    c->pilot_ratio = ratio;
    c->model_error = ratio * run->linear_error;
    if (c->model_error > run->model_target) {
      run->deferred_target = run->model_target / ratio;
      if (!f3r_choice_plain_search_may_wait(run)) st = f3r_choice_resume_plain_search(run, c, err);
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
  run->pair = far && run->chosen &&
              (run->deferred_target > 0.0 || /* no estimate yet: the search waits */
               PAIR_SKIP_FACTOR * run->linear_error > run->model_target);
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
  /* The relations were measured on the paper's modes. On the static correction the solver keeps
   * a tenth of its budget: on resonance.yaml, driven at a resonance for 0.25 s, minimal IDA at
   * rtol 1e-3 (2.1e-6 m on the benchmark's scenes) left 1 mode + 3 shapes (the fixed-free
   * set then) 2.2e-5 m from the converged path, at rtol 1e-4 2.4e-8 m for the same steps; a
   * pilot over the first tenth of the run saw nothing of it (the resonance builds up later). */
  if (run->unmeasured_basis) p->limit *= SOLVER_CHECK_SHARE;
  const double explicit_scale = f3r_explicit_scale_of(c->modes);
  for (int attempt = 0; attempt < 4; ++attempt) {
    const f3r_solver_relation* next = f3r_pick_solver(scene, run->kind, p->limit, explicit_scale);
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
                           (f3r_relation_cost(r, explicit_scale) +
                            (run->pilot_started ? 0.0
                                                : f3r_pilot_cost(run->kind, 0.1 * run->model_target,
                                                                 run->long_run)));
      const f3r_solver_relation* safe =
          f3r_pick_solver(scene, run->kind, SOLVER_CHECK_SHARE * budget, explicit_scale);
      if (safe &&
          f3r_relation_cost(safe, explicit_scale) <= f3r_relation_cost(r, explicit_scale) + check) {
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

/* The solver: the scene's own where it sets one, else the cheapest measured relation within the
 * budget the model and exact kinematics leave, kept unless none fits. */
static f3r_status choose_solver(choice_run* run, f3r_accuracy_choice* c, f3r_error* err) {
  const f3r_scene* scene = run->scene;
  solver_pick p = {0};
  p.budget = f3r_choice_solver_budget(run, c, c->model_error);
  c->formulation = scene->formulation;
  c->integrator = scene->integrator;
  c->rtol = scene->rtol;
  c->atol = scene->atol;
  snprintf(c->table, sizeof c->table, "%s", scene->table);
  if (!run->solver_open) {
    c->solver_error = f3r_solver_error_of(scene, run->kind);
    f3r_accuracy_append(c->summary, sizeof c->summary,
                        "solver: %s, %s, rtol %g, as the scene sets (measured error %.3g m)\n",
                        f3r_formulation_name(scene->formulation),
                        f3r_integrator_name(scene->integrator), scene->rtol, c->solver_error);
    return F3R_OK;
  }
  const f3r_status st = pick_relation(run, c, &p, err);
  if (st != F3R_OK) return st;
  const f3r_solver_relation* r = p.relation;
  if (!r) {
    c->solver_error = f3r_solver_error_of(scene, run->kind);
    f3r_accuracy_append(c->summary, sizeof c->summary,
                        "solver: no measured solver fits %.3g m; keeping %s, rtol %g\n", p.limit,
                        f3r_integrator_name(scene->integrator), scene->rtol);
    return F3R_OK;
  }
  c->formulation = r->formulation;
  c->integrator = r->integrator;
  c->rtol = r->rtol;
  if (!(scene->explicit_settings & F3R_EXPLICIT_ATOL)) c->atol = r->atol;
  snprintf(c->table, sizeof c->table, "%s", r->table);
  c->solver_error = fmax(r->error, p.measured);
  f3r_summarise_relation(run, c, &p);
  return F3R_OK;
}

/* The stages in order: what is open, the mode counts and their check, the summary of both, the
 * solver, then the estimate. */
f3r_status f3r_accuracy_choose(const f3r_scene* scene, double request, int commanded,
                               f3r_accuracy_choice* c, f3r_error* err) {
  memset(c, 0, sizeof *c);
  c->measured_error = NAN;
  if (!(request > 0.0) || !isfinite(request))
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "accuracy: the request must be a positive length (m)");
  c->request = request;
  f3r_scene s;
  choice_run run;
  open_choice(scene, request, commanded, &s, &run);
  c->excitation = run.excitation;
  f3r_status st = search_modes(&run, c, err);
  if (st == F3R_OK) st = check_modes(&run, c, err);
  if (st == F3R_OK) st = f3r_choice_compare_bases(&run, c, err);
  for (int i = 0; i < 3; ++i) {
    c->static_correction[i] = f3r_is_flexible(&s, i) && s.links[i].static_correction;
    c->shape_mix[i] = c->static_correction[i] && s.links[i].shape_mix_kind == F3R_SHAPE_MIXED
                          ? s.links[i].shape_mix
                          : NAN;
  }
  c->linear_evaluations = run.ms.evaluations;
  if (st == F3R_OK) {
    f3r_summarise_modes(&run, c);
    f3r_summarise_kinematics(&run, c);
    st = choose_solver(&run, c, err);
  }
  f3r_pilot_free(&run.pilot);
  f3r_mode_search_free(&run.ms);
  if (st == F3R_OK) f3r_summarise_estimate(&run, c);
  return st;
}

void f3r_accuracy_apply(const f3r_accuracy_choice* c, f3r_scene* s) {
  for (int i = 0; i < 3; ++i)
    if (f3r_is_flexible(s, i)) {
      s->links[i].modes = c->modes[i];
      s->links[i].static_correction = c->static_correction[i];
      if (c->static_correction[i] && isfinite(c->shape_mix[i])) {
        s->links[i].shape_mix_kind = F3R_SHAPE_MIXED;
        s->links[i].shape_mix = c->shape_mix[i];
      }
    }
  s->exact_kinematics = c->exact_kinematics;
  s->formulation = c->formulation;
  s->integrator = c->integrator;
  s->rtol = c->rtol;
  s->atol = c->atol;
  snprintf(s->table, sizeof s->table, "%s", c->table);
}

/* The links with shape_mix: fit, fitted at their resolved mode counts (f3r_shape_mix_fit). */
static f3r_status resolve_shape_mix(f3r_scene* scene, f3r_accuracy_choice* c, f3r_error* err) {
  const unsigned fit = f3r_shape_mix_open(scene);
  if (!fit) return F3R_OK;
  double mix[3];
  const f3r_status st = f3r_shape_mix_set_fitted(scene, fit, scene, mix, err);
  if (st != F3R_OK) return st;
  for (int i = 0; i < 3; ++i)
    if (fit >> i & 1)
      f3r_accuracy_append(
          c->summary, sizeof c->summary,
          "links[%d]: shape_mix fit -> %.6g (the load ratio of its slowest modes)\n", i, mix[i]);
  return F3R_OK;
}

/* Halvings of a commanded choice's excitation the knob tries when its pilot runs cannot follow
 * it (steps at limits.force pull a leg of a scene without end stops into its collapse guard
 * within the pilot's tenth of the run): 1000 N becomes at least 15.6 N. */
#define EXCITATION_HALVINGS 6

/* The choice for a scene with a request; a commanded one whose excitation the pilot runs cannot
 * follow is sized for half of it, and so on, saying so. */
static f3r_status choose_for_request(f3r_scene* scene, int commanded, f3r_accuracy_choice* c,
                                     f3r_error* err) {
  f3r_scene view = *scene; /* a view: the tables are scene's */
  f3r_status st = f3r_accuracy_choose(&view, scene->accuracy, commanded, c, err);
  char first[sizeof err->message] = "";
  double first_excitation = c->excitation;
  for (int k = 0; st != F3R_OK && c->excitation > 0.0 && k < EXCITATION_HALVINGS; ++k) {
    if (!first[0]) snprintf(first, sizeof first, "%s", err->message);
    view.accuracy_excitation = 0.5 * c->excitation;
    st = f3r_accuracy_choose(&view, scene->accuracy, commanded, c, err);
  }
  if (st == F3R_OK && first[0])
    f3r_accuracy_append(c->summary, sizeof c->summary,
                        "\nexcitation: %g N steps stopped a pilot run (%.80s...): sized for %g N",
                        first_excitation, first, c->excitation);
  if (st == F3R_OK) f3r_accuracy_apply(c, scene);
  return st;
}

static f3r_status resolve_modes(f3r_scene* scene, int commanded, f3r_accuracy_choice* c,
                                f3r_error* err) {
  if (scene->accuracy > 0.0) return choose_for_request(scene, commanded, c, err);
  unsigned chosen = 0;
  double tolerance = 0.0;
  for (int i = 0; i < 3; ++i)
    if (f3r_is_flexible(scene, i) && scene->links[i].modes == F3R_MODES_AUTO) {
      chosen |= 1u << i;
      tolerance = fmax(tolerance, scene->links[i].auto_tolerance);
    }
  if (!chosen) return F3R_OK;
  f3r_scene s = *scene; /* a view: the tables are scene's */
  for (int i = 0; i < 3; ++i)
    if (chosen >> i & 1) s.links[i].modes = 1;
  const f3r_status st = f3r_accuracy_modes(&s, chosen, -tolerance, c->modes, &c->model_error,
                                           &c->extent, &c->linear_evaluations, err);
  if (st != F3R_OK) return st;
  int corrected = 1; /* the search's reference (accuracy_search.c) */
  for (int i = 0; i < 3; ++i)
    if (chosen >> i & 1) corrected &= s.links[i].static_correction != 0;
  const char* reference = corrected ? "2r + 2" : "3r + 3";
  c->estimated_error = c->model_error;
  c->request_met = 1; /* no request: auto_tolerance, of the path's extent, decides */
  snprintf(c->brief, sizeof c->brief,
           "modes auto: %d/%d/%d (linearised path within %.3g m of %s modes, auto_tolerance %g "
           "of its extent %.3g m)",
           c->modes[0], c->modes[1], c->modes[2], c->model_error, reference, tolerance, c->extent);
  for (int i = 0; i < 3; ++i) {
    if (chosen >> i & 1) scene->links[i].modes = c->modes[i];
    if (chosen >> i & 1)
      f3r_accuracy_append(c->summary, sizeof c->summary,
                          "links[%d]: modes auto -> %d (linearised path within %.3g m of %s modes: "
                          "auto_tolerance %g of its extent %.3g m)\n",
                          i, c->modes[i], c->model_error, reference, tolerance, c->extent);
  }
  return F3R_OK;
}

f3r_status f3r_accuracy_resolve(f3r_scene* scene, int commanded, f3r_accuracy_choice* choice,
                                f3r_error* err) {
  f3r_accuracy_choice local;
  f3r_accuracy_choice* c = choice ? choice : &local;
  memset(c, 0, sizeof *c);
  c->measured_error = NAN;
  const f3r_status st = resolve_modes(scene, commanded, c, err);
  return st == F3R_OK ? resolve_shape_mix(scene, c, err) : st;
}

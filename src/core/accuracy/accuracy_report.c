/* The accuracy knob's report (accuracy.h's summary and brief): the prose that says what was
 * chosen and why, written from the facts the stages of accuracy.c gathered. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "accuracy_parts.h"

void f3r_accuracy_append(char* text, size_t size, const char* fmt, ...) {
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
    if (set & F3R_EXPLICIT_FORMULATION) f3r_accuracy_append(fixed, sizeof fixed, " formulation");
    if (set & F3R_EXPLICIT_INTEGRATOR) f3r_accuracy_append(fixed, sizeof fixed, " integrator");
    if (set & F3R_EXPLICIT_RTOL) f3r_accuracy_append(fixed, sizeof fixed, " rtol");
    if (set & F3R_EXPLICIT_TABLE) f3r_accuracy_append(fixed, sizeof fixed, " table");
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

/* Counts a link each, "r/r/r", into text. */
static void counts(const int* modes, char* text, size_t size) {
  snprintf(text, size, "%d/%d/%d", modes[0], modes[1], modes[2]);
}

/* The summary's line on the basis, where the knob compared the static correction with the
 * paper's modes: each one's counts, estimate and relative cost, and which it kept. */
static void summarise_basis(const choice_run* run, f3r_accuracy_choice* c) {
  if (!run->correctable) return;
  if (run->least_corrected_cost > 0.0) {
    char plain[32];
    counts(run->plain_modes, plain, sizeof plain);
    f3r_accuracy_append(
        c->summary, sizeof c->summary,
        "basis: the paper's modes %s (cost %.3g) cost no more than the least "
        "static correction, 1 mode + static shapes (cost %.3g): %s; cost "
        "is sqrt(highest linearised frequency) x coordinates\n",
        plain, run->plain_cost, run->least_corrected_cost,
        run->corrected_first ? "its search, run first, is dropped" : "not searched");
    return;
  }
  char plain[32], corrected[32], p_est[64] = "no count within the share",
                                 c_est[64] = "no count within the share";
  counts(run->plain_modes, plain, sizeof plain);
  counts(run->corrected_modes, corrected, sizeof corrected);
  if (run->plain_beyond) { /* their search again was not needed */
    snprintf(plain, sizeof plain, "with %d or more on a link", run->plain_beyond);
    snprintf(p_est, sizeof p_est, "cost at least %.3g with their solver", run->plain_cost);
  } else if (run->plain_found)
    snprintf(p_est, sizeof p_est, "%.3g m, cost %.3g x %.2g", run->plain_error, run->plain_cost,
             run->plain_solver_cost);
  if (run->corrected_found)
    snprintf(c_est, sizeof c_est, "%.3g m, cost %.3g x %.2g", run->corrected_error,
             run->corrected_cost, run->corrected_solver_cost);
  const int kept = c->static_correction[0] || c->static_correction[1] || c->static_correction[2];
  f3r_accuracy_append(c->summary, sizeof c->summary,
                      "basis: %s: the paper's modes %s (%s) against modes %s + static shapes "
                      "(%s); cost is sqrt(highest linearised frequency) x coordinates x the "
                      "measured cost of the solver the rest of the request leaves (a tenth of it "
                      "on the static correction)\n",
                      kept ? "the static correction" : "the paper's modes", plain, p_est, corrected,
                      c_est);
  if (kept && run->wide_model)
    f3r_accuracy_append(c->summary, sizeof c->summary,
                        "basis: its estimate takes %.2g of the request, past the model's share: "
                        "with the tighter solver it leaves room for, it costs less than the "
                        "counts within the share\n",
                        run->corrected_error / run->request);
}

/* The summary's lines on the request, the mode counts and the pilot that checked them. */
void f3r_summarise_modes(const choice_run* run, f3r_accuracy_choice* c) {
  char* text = c->summary;
  const size_t size = sizeof c->summary;
  const f3r_mode_search* ms = &run->ms;
  f3r_accuracy_append(
      text, size,
      "accuracy %g m on the end-effector path (shares: model %g, kinematics %g, solver %g)\n",
      run->request, F3R_ACCURACY_MODEL_SHARE, F3R_ACCURACY_KINEMATICS_SHARE,
      F3R_ACCURACY_SOLVER_SHARE);
  for (int i = 0; i < 3; ++i) {
    char shapes[80] = "";
    if (c->static_correction[i] && isfinite(c->shape_mix[i]))
      snprintf(shapes, sizeof shapes, " + 1 static shape (tip force + %.3g uniform load)",
               c->shape_mix[i]);
    else if (c->static_correction[i])
      snprintf(shapes, sizeof shapes, " + %d static shapes",
               f3r_link_static_shapes(run->scene->links[i].model));
    if (!f3r_is_flexible(run->scene, i))
      f3r_accuracy_append(text, size, "links[%d]: rigid\n", i);
    else
      f3r_accuracy_append(text, size, "links[%d]: %d mode%s%s%s\n", i, c->modes[i],
                          c->modes[i] == 1 ? "" : "s", shapes,
                          run->chosen >> i & 1 ? "" : ", as the scene sets");
  }
  summarise_basis(run, c);
  if (run->chosen && run->excitation > 0.0)
    f3r_accuracy_append(text, size,
                        "modes: commands come from outside: sized for leg-force steps of %g N "
                        "(accuracy.excitation, else limits.force); the closed-loop measurement "
                        "says whether the commands stayed within that\n",
                        run->excitation);
  if (run->chosen && run->impacts)
    f3r_accuracy_append(
        text, size,
        "modes: end stops: impacts are outside the linear estimate, and past one the path need "
        "not converge in the mode count; sized for the path between impacts (the measured run "
        "says whether it converges)\n");
  else if (run->chosen && ms->at_rest)
    f3r_accuracy_append(
        text, size, "modes: nothing excites the scene (no inputs, initial rates or deflections)\n");
  else if (run->chosen)
    f3r_accuracy_append(
        text, size,
        "modes: the %s-order linearised path is within %.3g m of the same with %d modes%s (path "
        "extent %.3g m, %d linear models)\n",
        ms->order == 2 ? "second" : "first", run->linear_error, ms->ref_r,
        ms->corrected ? " and the static shapes" : "", c->extent, c->linear_evaluations);
  if (c->pilot && run->pair)
    f3r_accuracy_append(
        text, size,
        "pilot: the path leaves the initial pose (%.3g m); nonlinear runs at the least mode "
        "counts over "
        "the first %.0f%% of it, carried to the whole, scale the linear estimate by %.3g\n",
        c->extent, 100.0 * F3R_PILOT_SHARE, c->pilot_ratio);
  else if (run->pair_skipped)
    f3r_accuracy_append(
        text, size,
        "pilot: the path leaves the initial pose (%.3g m), but its linear estimate is below "
        "1/%g of the "
        "model's share, beyond any nonlinear ratio measured; not checked\n",
        c->extent, PAIR_SKIP_FACTOR);
}

/* The summary's line on exact kinematics: on, or off as the scene sets and how its effect is
 * counted. */
void f3r_summarise_kinematics(const choice_run* run, f3r_accuracy_choice* c) {
  char* text = c->summary;
  const size_t size = sizeof c->summary;
  if (!run->any_flexible)
    f3r_accuracy_append(text, size, "exact kinematics: no flexible link\n");
  else if (run->kinematics_open && run->impacts)
    f3r_accuracy_append(text, size, "exact kinematics: on (the most faithful model)\n");
  else if (run->kinematics_open)
    f3r_accuracy_append(
        text, size,
        "exact kinematics: on: it costs no measurable CPU time (the same steps and time as "
        "without it on the shipped scenes), so its part of the error is removed, not estimated\n");
  else if (!run->kinematics_off)
    f3r_accuracy_append(text, size, "exact kinematics: on, as the scene sets\n");
  else if (run->kinematics_linear_only)
    f3r_accuracy_append(
        text, size,
        "exact kinematics: off, as the scene sets; its linear estimate %.3g m, below 1/%g of "
        "its share "
        "%.3g m (beyond any ratio a pilot measured), is counted unchecked\n",
        c->kinematics_linear, KINEMATICS_SKIP_FACTOR, F3R_ACCURACY_KINEMATICS_SHARE * run->request);
  else if (!run->kinematics)
    f3r_accuracy_append(
        text, size,
        "exact kinematics: off, as the scene sets; its effect is second order in the deflections "
        "and the path stays near the initial pose: not estimated\n");
  else {
    char linear[64] = "";
    if (c->kinematics_linear > 0.0)
      snprintf(linear, sizeof linear, ", its linear estimate %.3g m", c->kinematics_linear);
    f3r_accuracy_append(
        text, size,
        "exact kinematics: off, as the scene sets; a pilot estimates its effect at %.3g m%s, "
        "counted in the estimate\n",
        c->kinematics_effect, linear);
  }
}

/* The summary's lines on the relation taken: where it was measured, and how it was checked. */
void f3r_summarise_relation(const choice_run* run, f3r_accuracy_choice* c, const solver_pick* p) {
  char* text = c->summary;
  const size_t size = sizeof c->summary;
  const f3r_solver_relation* r = p->relation;
  f3r_accuracy_append(
      text, size,
      "solver: %s, %s%s%s, rtol %g, atol %g: the cheapest measured within %.3g m (at most %.3g "
      "m on "
      "the %d %s benchmark scenes; cost %.2g of minimal IDA at 1e-6; measured on %s)\n",
      f3r_formulation_name(r->formulation), f3r_integrator_name(r->integrator),
      r->table[0] ? " " : "", r->table, r->rtol, c->atol, p->limit, r->error, r->scenes, r->kind,
      r->cost, f3r_solver_relations_source);
  if (run->unmeasured_basis)
    f3r_accuracy_append(text, size,
                        "solver: the relations were measured on the paper's modes; on the static "
                        "correction it keeps %g of its budget %.3g m\n",
                        SOLVER_CHECK_SHARE, p->budget);
  if (run->impacts)
    f3r_accuracy_append(
        text, size,
        "solver: impacts amplify the solver's error (up to %g times on end_stop_impact); "
        "the budget %.3g m is divided by that\n",
        IMPACT_AMPLIFICATION, p->budget);
  else if (p->checked && run->long_run)
    f3r_accuracy_append(
        text, size,
        "solver: the run is longer than the benchmark's scenes (%g s); a pilot over its first "
        "%.0f%% measures %.3g m for it over the run\n",
        BENCHMARK_DURATION, 100.0 * F3R_PILOT_SHARE, p->measured);
  else if (p->checked)
    f3r_accuracy_append(text, size, "solver: the pilot measures %.3g m for it over the run\n",
                        p->measured);
  else if (p->skipped_check)
    f3r_accuracy_append(
        text, size,
        "solver: rtol %g, the cheapest within the budget, would need a pilot's check that "
        "costs more than this one does over it; this one's measured error is below %g of "
        "the budget: not checked\n",
        p->skipped_check->rtol, SOLVER_CHECK_SHARE);
  else if (run->ms.far)
    f3r_accuracy_append(text, size,
                        "solver: its measured error is below %g of the budget; not checked\n",
                        SOLVER_CHECK_SHARE);
}

/* The estimate's total, whether it meets the request (and what holds it where it does not), and
 * the one-line brief. */
void f3r_summarise_estimate(const choice_run* run, f3r_accuracy_choice* c) {
  const double request = run->request;
  const double total =
      c->model_error + c->kinematics_error + (isfinite(c->solver_error) ? c->solver_error : 0.0);
  c->estimated_error = total;
  c->request_met = total <= request;
  f3r_accuracy_append(
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
    f3r_accuracy_append(c->summary, sizeof c->summary,
                        "\nnot met: the estimate is %.3g times the request; %s", total / request,
                        why);
  }
  char how[64] = "linear estimate";
  if (run->impacts)
    snprintf(how, sizeof how, "the most faithful: impacts");
  else if (c->pilot)
    snprintf(how, sizeof how, "linear estimate x %.3g from the pilot", c->pilot_ratio);
  snprintf(c->brief, sizeof c->brief,
           "accuracy %g m: modes %d/%d/%d%s (%s), exact kinematics %s, %s %s%s%s rtol %g; "
           "estimated %.3g m%s",
           request, c->modes[0], c->modes[1], c->modes[2],
           c->static_correction[0] || c->static_correction[1] || c->static_correction[2]
               ? " + static shapes"
               : "",
           how, c->exact_kinematics ? "on" : "off", f3r_formulation_name(c->formulation),
           f3r_integrator_name(c->integrator), c->table[0] ? " " : "", c->table, c->rtol, total,
           run->impacts ? " without the impacts" : "");
  if (!c->request_met)
    f3r_accuracy_append(c->brief, sizeof c->brief, "; NOT MET (%.3g x the request)",
                        total / request);
}

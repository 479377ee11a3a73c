/* The accuracy knob's basis (accuracy_choice.h): the paper's modes against the static correction
 * on the links the scene leaves open, with the paper's modes' search beyond r = PLAIN_FIRST_MOST
 * waiting for the corrected one where it can (f3r_choice_plain_search_may_wait). Runs once before
 * a simulation, so it allocates freely. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accuracy_parts.h"

/* The uniform counts the paper's modes are tried at before the corrected search: 1 and 2. r = 3
 * (its reference has 12 modes a link, the choosing's largest linear model) waits with the rest:
 * on the fixed-free links the knob corrects, the paper's 3 modes won no request of the
 * benchmark, and where they do win, the corrected search has run for nothing (the same choice).
 * Paper simulation 3 at 1e-4 m: 9 linear models -> 7, the choosing 5.2 -> 4.6 ms. Where they fit
 * at r = 3 and cost no more than the least pair, cheaper_than_any_correction used to keep them
 * unweighed against the mixed shape and the solvers; the full comparison now runs there
 * (resonance.yaml at 3e-4 m: 1 mode + the mixed shape, 23.5 -> 14.8 ms and 1.4e-4 -> 4.2e-6 m). */
#define PLAIN_FIRST_MOST 2

/* The links whose basis the knob may correct: chosen, fixed-free and left open by the scene. A
 * fixed-pinned link's own shapes pay only below about 4e-8 m, where the knob's requests do not
 * reach (docs/benchmarks/basis_convergence.md). */
static unsigned correctable_links(const choice_run* run) {
  unsigned links = 0;
  for (int i = 0; i < 3; ++i)
    if ((run->chosen >> i & 1) && run->scene->links[i].model == F3R_LINK_FIXED_FREE &&
        !run->scene->links[i].static_correction &&
        !(run->scene->explicit_settings & (F3R_EXPLICIT_STATIC_CORRECTION << i)))
      links |= 1u << i;
  return links;
}

/* The paper's modes searched again within the pilot's target, if that was deferred. */
f3r_status f3r_choice_resume_plain_search(choice_run* run, f3r_accuracy_choice* c, f3r_error* err) {
  if (!(run->deferred_target > 0.0)) return F3R_OK;
  const f3r_status st = f3r_mode_search_run(run->s, &run->ms, run->deferred_target, c->modes,
                                            &run->linear_error, err);
  c->model_error = c->pilot_ratio * run->linear_error;
  run->deferred_target = 0.0;
  return st;
}

/* Whether the search again can wait for the corrected one (compare_correction's conditions for
 * searching that basis at all). */
int f3r_choice_plain_search_may_wait(const choice_run* run) {
  return !run->ms.at_rest && !run->impacts && correctable_links(run);
}

/* The correctable links' static correction as one mixed shape (beam_basis.h), its load ratio
 * fitted at the counts `modes` (f3r_shape_mix_fit): it keeps the pair's first frequency and drops
 * its stiff combination, whose 3 kHz modes set IDA's step (about half the steps on paper
 * simulation 3: docs/benchmarks/fast_shapes.md). */
static f3r_status mix_corrected_shapes(const choice_run* run, const int modes[3],
                                       f3r_scene* corrected, f3r_error* err) {
  f3r_scene at = *corrected; /* a view of the same tables */
  at.accuracy = 0.0;
  for (int i = 0; i < 3; ++i)
    if (f3r_is_flexible(&at, i)) at.links[i].modes = modes[i];
  return f3r_shape_mix_set_fitted(&at, run->correctable, corrected, NULL, err);
}

/* The same counts, uniform r, with one mixed shape instead of the pair (mix_corrected_shapes on
 * `pair`, the scene with the pair), estimated against the pair's own reference there (2 r + 2
 * modes and the pair): taken into `corrected`, ms and run's candidate where it fits target and
 * costs less with its solver. On paper simulation 3 it halves the run's steps at 1e-4 m (r = 1)
 * and at 1e-5 m (r = 2). */
static f3r_status try_mixed_shape(choice_run* run, const f3r_accuracy_choice* c,
                                  const f3r_scene* pair, f3r_scene* corrected, f3r_mode_search* ms,
                                  double ratio, int r, double target, double* estimate,
                                  f3r_error* err) {
  int at_r[3], fits = 0;
  f3r_mode_search_uniform(ms, r, at_r);
  if (r < 1 || r > 3) return F3R_OK;
  const unsigned kept_mixed = ms->mixed;
  f3r_scene mixed = *pair; /* a view of the same tables */
  f3r_status st = mix_corrected_shapes(run, at_r, &mixed, err);
  ms->mixed = 0;
  if (st == F3R_OK) st = f3r_mode_search_fits(pair, ms, r, 0.0, &fits, err); /* the ref */
  ms->mixed = run->correctable;
  if (st == F3R_OK) st = f3r_mode_search_path(&mixed, ms, at_r, ms->order, ms->path, err);
  const double e = st == F3R_OK ? f3r_max_distance(ms->path, ms->ref, ms->count) : 0.0;
  double cost = 0.0;
  if (st == F3R_OK && e <= target / ratio) st = f3r_basis_cost(&mixed, at_r, &cost, err);
  const double solver = f3r_choice_solver_cost(run, c, at_r, ratio * e, 1);
  if (st != F3R_OK || !(cost > 0.0) ||
      !(cost * solver < run->corrected_cost * run->corrected_solver_cost)) {
    ms->mixed = kept_mixed;
    return st;
  }
  *corrected = mixed;
  *estimate = e;
  memcpy(run->corrected_modes, at_r, sizeof at_r);
  run->corrected_error = ratio * e;
  run->corrected_cost = cost;
  run->corrected_solver_cost = solver;
  return F3R_OK;
}

/* The uniform count of counts on the correctable links, 0 where they differ. */
static int uniform_count(const choice_run* run, const f3r_mode_search* ms, const int modes[3]) {
  int r = 0, at_r[3];
  for (int i = 0; i < 3 && !r; ++i)
    if (run->correctable >> i & 1) r = modes[i];
  f3r_mode_search_uniform(ms, r, at_r);
  return memcmp(at_r, modes, sizeof at_r) ? 0 : r;
}

/* The model's share is where the search starts, not a bound. Fewer corrected modes whose estimate
 * fits what the request leaves beside exact kinematics' error and the tightest measured solver
 * (f3r_choice_wide_model_target) are weighed too, with the pair and with the mixed shape, and
 * taken where they cost less with the solver they leave room for. Paper simulation 3 with
 * fixed-free links at 1e-5 m: 2 modes + the pair within the share (estimate 8.6e-7 m, minimal IDA
 * at rtol 1e-4, 43 780 steps, 62 ms with the choosing) against 1 mode + the mixed shape past it
 * (8.3e-6 m, Dormand-Prince 5(4) at rtol 1e-4 within a tenth of the 1.7e-6 m left, 6 613 steps,
 * 33 ms). Where neither is taken, ms keeps the reference of the counts that were. */
static f3r_status try_fewer_corrected(choice_run* run, const f3r_accuracy_choice* c,
                                      const f3r_scene* pair, f3r_scene* corrected,
                                      f3r_mode_search* ms, double ratio, double* estimate,
                                      f3r_error* err) {
  const double wide = f3r_choice_wide_model_target(run, c);
  if (!(wide > run->model_target)) return F3R_OK;
  const size_t bytes = (size_t)ms->count * 3 * sizeof(double);
  double* kept_ref = malloc(bytes);
  if (!kept_ref) return f3r_error_set(err, F3R_ERR_MEMORY, "accuracy: out of memory");
  memcpy(kept_ref, ms->ref, bytes);
  const int kept_ref_r = ms->ref_r;
  const unsigned kept_mixed = ms->mixed;
  const double before = run->corrected_cost * run->corrected_solver_cost;
  int modes[3];
  double e = 0.0, cost = 0.0;
  ms->mixed = 0;
  f3r_status st = f3r_mode_search_run(pair, ms, wide / ratio, modes, &e, err);
  ms->mixed = kept_mixed;
  const int found = st == F3R_OK && f3r_mode_search_found(ms, modes);
  if (found && (memcmp(modes, run->corrected_modes, sizeof modes) || kept_mixed))
    st = f3r_basis_cost(pair, modes, &cost, err);
  const double solver = f3r_choice_solver_cost(run, c, modes, ratio * e, 1);
  if (st == F3R_OK && cost > 0.0 && cost * solver < before) {
    *corrected = *pair;
    ms->mixed = 0;
    memcpy(run->corrected_modes, modes, sizeof modes);
    run->corrected_error = ratio * e;
    run->corrected_cost = cost;
    run->corrected_solver_cost = solver;
    *estimate = e;
  }
  if (st == F3R_OK && found)
    st = try_mixed_shape(run, c, pair, corrected, ms, ratio, uniform_count(run, ms, modes), wide,
                         estimate, err);
  run->wide_model = run->corrected_cost * run->corrected_solver_cost < before;
  if (!run->wide_model) { /* the reference of the counts kept, for the summary and the pilot */
    memcpy(ms->ref, kept_ref, bytes);
    ms->ref_r = kept_ref_r;
  }
  free(kept_ref);
  return st;
}

/* The cost of the least static correction: one mode + shapes on the correctable links. */
static f3r_status least_correction_cost(const choice_run* run, const f3r_scene* corrected,
                                        double* cost, f3r_error* err) {
  int least[3];
  f3r_mode_search_least(&run->ms, least);
  for (int i = 0; i < 3; ++i)
    if (run->correctable >> i & 1) least[i] = 1;
  return f3r_basis_cost(corrected, least, cost, err);
}

/* The cheapest solver cost any model error leaves at these counts: the most budget; 1 where no
 * relation fits (the cost f3r_choice_solver_cost then gives). */
static double cheapest_solver_cost(const choice_run* run, const f3r_accuracy_choice* c,
                                   const int modes[3]) {
  return fmin(1.0, f3r_choice_solver_cost(run, c, modes, 0.0, 0));
}

/* What the paper's modes' search found: its counts, estimate, and whether it fit. */
static void note_plain_counts(choice_run* run, const f3r_accuracy_choice* c) {
  memcpy(run->plain_modes, c->modes, sizeof run->plain_modes);
  run->plain_error = c->model_error;
  run->plain_found = f3r_mode_search_found(&run->ms, c->modes);
}

/* Clears run->correctable when the paper's modes the search found cost no more than the least
 * corrected basis (its cost only grows with the modes): then no corrected search is needed. On
 * the shipped scenes where the paper's modes win, that spares 10 to 45 ms of choosing. */
static f3r_status cheaper_than_any_correction(choice_run* run, const f3r_scene* corrected,
                                              const f3r_accuracy_choice* c, f3r_error* err) {
  int least[3];
  f3r_mode_search_least(&run->ms, least);
  if (!memcmp(least, c->modes, sizeof least)) { /* the paper's least modes: nothing is fewer */
    run->correctable = 0;
    return F3R_OK;
  }
  double least_cost = 0.0;
  f3r_status st = f3r_basis_cost(run->s, c->modes, &run->plain_cost, err);
  if (st == F3R_OK) st = least_correction_cost(run, corrected, &least_cost, err);
  if (st == F3R_OK && run->plain_cost <= least_cost) run->least_corrected_cost = least_cost;
  return st;
}

f3r_status f3r_choice_plain_first_part(choice_run* run, double target, int* fits, f3r_error* err) {
  *fits = 0;
  f3r_status st = F3R_OK;
  for (int r = 1; r <= PLAIN_FIRST_MOST && !*fits && st == F3R_OK; ++r)
    st = f3r_mode_search_fits(run->s, &run->ms, r, target, fits, err);
  return st;
}

/* Where the paper's modes wait for their search again (run->deferred_target): the search's
 * first part, r = 1 .. PLAIN_FIRST_MOST on every chosen link each against its own reference,
 * runs now; where one fits, the whole search runs now (the order of choosing is today's, and
 * that part comes from the memo). Where none fits, the rest (r = 3 against 12 modes, then a
 * bisection against 20, the costly part) waits for the corrected search, and *least_cost gets
 * the least static correction's cost. */
static f3r_status plain_search_first_part(choice_run* run, const f3r_scene* corrected,
                                          f3r_accuracy_choice* c, double* least_cost,
                                          f3r_error* err) {
  *least_cost = 0.0;
  if (!(run->deferred_target > 0.0)) return F3R_OK;
  int fits = 0;
  const f3r_status st = f3r_choice_plain_first_part(run, run->deferred_target, &fits, err);
  if (st != F3R_OK) return st;
  if (fits || !f3r_mode_search_found(&run->ms, c->modes))
    return f3r_choice_resume_plain_search(run, c, err);
  return least_correction_cost(run, corrected, least_cost, err);
}

/* The least cost the paper's modes can have once searched again: the counts found so far with the
 * cheapest solver any model error leaves (the most budget; 1 where none fits), or the least
 * counts with r_lo on one chosen link (on all of them far from the pose, where the search keeps
 * its counts uniform), whichever is more. The search again needs at least r_lo modes on some
 * link: `missed` + 1, as the uniform counts up to it missed, and at least the uniform count found
 * so far, since every count below it missed a looser target. That it keeps every link at least at
 * the count found so far is the search's own assumption that the difference falls with the
 * modes. */
static f3r_status plain_least_cost(choice_run* run, const f3r_accuracy_choice* c, int missed,
                                   double* cost, int* r_least, f3r_error* err) {
  int r_lo = missed + 1, least[3];
  for (int i = 0; i < 3; ++i)
    if ((run->chosen >> i & 1) && c->modes[i] > r_lo) r_lo = c->modes[i];
  f3r_mode_search_least(&run->ms, least);
  *r_least = r_lo;
  double so_far = 0.0;
  f3r_status st = f3r_basis_cost(run->s, c->modes, &so_far, err);
  double at_r_lo = 0.0; /* the cheapest way to have r_lo on some chosen link (far: on all) */
  if (run->ms.far) {
    int modes[3];
    f3r_mode_search_uniform(&run->ms, r_lo, modes);
    if (st == F3R_OK) st = f3r_basis_cost(run->s, modes, &at_r_lo, err);
    at_r_lo *= cheapest_solver_cost(run, c, modes);
  } else {
    for (int i = 0; i < 3 && st == F3R_OK; ++i) {
      if (!(run->chosen >> i & 1) || !f3r_is_flexible(run->s, i)) continue;
      int modes[3];
      memcpy(modes, least, sizeof modes);
      modes[i] = r_lo > least[i] ? r_lo : least[i];
      double basis = 0.0;
      st = f3r_basis_cost(run->s, modes, &basis, err);
      const double total = basis * cheapest_solver_cost(run, c, modes);
      if (at_r_lo == 0.0 || total < at_r_lo) at_r_lo = total;
    }
  }
  *cost = fmax(so_far * cheapest_solver_cost(run, c, c->modes), at_r_lo);
  return st;
}

/* Whether the corrected basis costs less than the paper's modes can once searched again: their
 * uniform counts are probed one more at a time up to r = 3 (the last against its own reference,
 * 12 modes) while a miss can still raise their least cost past the corrected one's. Paper
 * simulation 3 with fixed-free links at 1e-5 m: r = 3 misses, and the least cost at 4 modes
 * spares the search against 20 modes. */
static f3r_status corrected_cheaper(choice_run* run, const f3r_accuracy_choice* c, int* cheaper,
                                    f3r_error* err) {
  *cheaper = 0;
  const double corrected = run->corrected_cost * run->corrected_solver_cost;
  for (int missed = PLAIN_FIRST_MOST;; ++missed) {
    double at_least = 0.0;
    int r_least = 0, fits = 0;
    f3r_status st = plain_least_cost(run, c, missed, &at_least, &r_least, err);
    if (st != F3R_OK) return st;
    if (corrected < at_least) {
      *cheaper = 1;
      run->plain_beyond = r_least;
      run->plain_cost = at_least;
      return F3R_OK;
    }
    if (r_least > missed + 1 || missed + 1 > 3) return F3R_OK;
    if ((st = f3r_mode_search_fits(run->s, &run->ms, missed + 1, run->deferred_target, &fits,
                                   err)) != F3R_OK ||
        fits)
      return st;
  }
}

/* After the corrected search, where the rest of the paper's modes' search waited: it runs only
 * where they could still cost less (corrected_cheaper). Where it runs and they cost no more than
 * the least correction, they are kept as cheaper_than_any_correction keeps them. */
static f3r_status settle_plain_search(choice_run* run, f3r_accuracy_choice* c, double least_cost,
                                      f3r_error* err) {
  if (!(run->deferred_target > 0.0)) return F3R_OK;
  run->corrected_first = 1;
  f3r_status st = F3R_OK;
  int cheaper = 0;
  if (run->corrected_found && (st = corrected_cheaper(run, c, &cheaper, err)) != F3R_OK) return st;
  if (cheaper) {
    run->deferred_target = 0.0;
    return F3R_OK;
  }
  st = f3r_choice_resume_plain_search(run, c, err);
  note_plain_counts(run, c);
  if (st == F3R_OK) st = f3r_basis_cost(run->s, c->modes, &run->plain_cost, err);
  if (st == F3R_OK && run->plain_found && run->plain_cost <= least_cost)
    run->least_corrected_cost = least_cost;
  return st;
}

/* The same search with the static shapes on the correctable links, after the pilot: its ratio
 * of the nonlinear to the linear difference scales both bases' estimates alike (it measures how
 * the motion amplifies a truncation, not the basis). The cheaper basis that fits the model's
 * share stays in run->ms and run->s (the paper's modes where neither is cheaper). */
f3r_status f3r_choice_compare_bases(choice_run* run, f3r_accuracy_choice* c, f3r_error* err) {
  /* At any run length: on runs longer than the benchmark's scenes the estimates fell short
   * (free_vibration_long over 2 s at 1e-5 m: 8.3e-6 m where they said 2.8e-6), and refusing the
   * correction there made paper simulation 3 over 1.5 s cost 270 times its 0.5 s run. The
   * check (f3r_accuracy_check_scene) measures what the estimate cannot promise. */
  run->correctable = run->ms.at_rest || run->impacts ? 0u : correctable_links(run);
  if (!run->correctable) return f3r_choice_resume_plain_search(run, c, err);
  f3r_scene corrected = *run->s; /* a view of the same tables */
  for (int i = 0; i < 3; ++i)
    if (run->correctable >> i & 1) corrected.links[i].static_correction = 1;
  f3r_mode_search ms;
  double estimate = 0.0, least_cost = 0.0;
  const double ratio = c->pilot_ratio > 1.0 ? c->pilot_ratio : 1.0;
  f3r_status st = plain_search_first_part(run, &corrected, c, &least_cost, err);
  if (st != F3R_OK) return st;
  note_plain_counts(run, c);
  if (!(run->deferred_target > 0.0) && run->plain_found &&
      (st = cheaper_than_any_correction(run, &corrected, c, err)) != F3R_OK)
    return st;
  if (run->least_corrected_cost > 0.0 || !run->correctable) return F3R_OK;
  st = f3r_mode_search_init(&corrected, run->chosen, &run->ms, &ms, err);
  if (st == F3R_OK)
    st = f3r_mode_search_run(&corrected, &ms, run->model_target / ratio, run->corrected_modes,
                             &estimate, err);
  run->corrected_error = ratio * estimate;
  run->corrected_found = st == F3R_OK && f3r_mode_search_found(&ms, run->corrected_modes);
  if (st == F3R_OK && run->corrected_found)
    st = f3r_basis_cost(&corrected, run->corrected_modes, &run->corrected_cost, err);
  run->corrected_solver_cost =
      f3r_choice_solver_cost(run, c, run->corrected_modes, run->corrected_error, 1);
  const f3r_scene pair = corrected;
  if (st == F3R_OK && run->corrected_found)
    st = try_mixed_shape(run, c, &pair, &corrected, &ms, ratio,
                         uniform_count(run, &ms, run->corrected_modes), run->model_target,
                         &estimate, err);
  if (st == F3R_OK && run->corrected_found)
    st = try_fewer_corrected(run, c, &pair, &corrected, &ms, ratio, &estimate, err);
  if (st == F3R_OK) st = settle_plain_search(run, c, least_cost, err);
  run->plain_solver_cost =
      run->plain_beyond ? 1.0
                        : f3r_choice_solver_cost(run, c, run->plain_modes, run->plain_error, 0);
  const int take =
      st == F3R_OK && run->corrected_found && !(run->least_corrected_cost > 0.0) &&
      (!run->plain_found || run->plain_beyond ||
       run->corrected_cost * run->corrected_solver_cost < run->plain_cost * run->plain_solver_cost);
  run->ms.evaluations += ms.evaluations;
  if (!take) {
    f3r_mode_search_free(&ms);
    return st;
  }
  ms.evaluations = run->ms.evaluations;
  f3r_mode_search_free(&run->ms);
  run->ms = ms; /* the search's paths move with it */
  *run->s = corrected;
  memcpy(c->modes, run->corrected_modes, sizeof c->modes);
  run->linear_error = estimate;
  c->model_error = run->corrected_error;
  /* the pilot's runs and reference are of the paper's basis: a solver check starts its own */
  f3r_pilot_free(&run->pilot);
  run->pilot_started = 0;
  run->unmeasured_basis = 1;
  return F3R_OK;
}

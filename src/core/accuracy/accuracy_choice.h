/* What the stages of one accuracy choice share (accuracy.c), and the report they write
 * (accuracy_report.c): the summary's prose lives apart from the choosing. Private to the layer. */
#ifndef FLEX3RPR_ACCURACY_CHOICE_H
#define FLEX3RPR_ACCURACY_CHOICE_H

#include "accuracy_parts.h"

/* The knob's measured thresholds, which the choosing applies and the report cites. */
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

/* What the stages of one choice share: the scene and its working copy (the chosen links' modes
 * a placeholder), what the scene leaves open, the mode search and the pilot (freed at the end),
 * and the facts the summary reports. */
typedef struct {
  const f3r_scene* scene; /* the caller's */
  f3r_scene* s;           /* the working copy */
  double request;
  double model_target; /* m: the model's share of the request */
  const char* kind;    /* the solver relations' kind: rigid, flexible or commanded */
  double excitation;   /* N: the leg-force steps a commanded choice is sized for, or 0 */
  unsigned chosen;     /* the links whose mode counts the knob chooses */
  int any_flexible;
  int kinematics_open, kinematics_off, solver_open;
  f3r_mode_search ms;
  /* The static correction against the paper's modes, where the knob may choose it: the links it
   * may go on, each basis's counts, linear estimate and relative cost (f3r_basis_cost) */
  unsigned correctable;
  int plain_modes[3], corrected_modes[3];
  int plain_found, corrected_found;
  double plain_error, corrected_error, plain_cost, corrected_cost;
  double plain_solver_cost, corrected_solver_cost; /* the solver each basis leaves room for */
  double least_corrected_cost; /* > 0: the search was spared, the paper's modes cost no more */
  int wide_model; /* the corrected counts fit past the model's share (try_fewer_corrected) */
  /* > 0: the pilot asked the paper's modes to be searched again within this target; beyond
   * r = PLAIN_FIRST_MOST (accuracy_basis.c) that waits for the corrected search
   * (settle_plain_search). plain_beyond > 0: it was not needed, as the paper's modes would need
   * that many on some link and cost at least plain_cost (with their solver) */
  double deferred_target;
  int plain_beyond;
  int corrected_first;    /* the corrected search ran while the paper's modes waited */
  int impacts;            /* end stops on a path that moves: the most faithful model */
  int long_run;           /* longer than the benchmark's scenes */
  int unmeasured_basis;   /* the static correction: the relations were measured on the paper's
                           * modes, so the solver keeps SOLVER_CHECK_SHARE of its budget */
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

/* The solver relations as costs (accuracy_solver.c). A relation's cost, an explicit integrator's
 * scaled by explicit_scale; the cheapest measured solver whose error fits `budget` among those the
 * scene leaves open; explicit integrators' cost scale at these mode counts; the solver's budget
 * beside a model error; the measured error of the scene's own fixed solver. */
double f3r_relation_cost(const f3r_solver_relation* r, double explicit_scale);
const f3r_solver_relation* f3r_pick_solver(const f3r_scene* s, const char* kind, double budget,
                                           double explicit_scale);
double f3r_explicit_scale_of(const int modes[3]);
double f3r_choice_solver_budget(const choice_run* run, const f3r_accuracy_choice* c,
                                double model_error);
double f3r_solver_error_of(const f3r_scene* s, const char* kind);
/* The relative cost of the solver a basis leaves room for: the cheapest measured
 * relation within the request less the model error and the kinematics', a tenth of that on the
 * static correction; 1 where the scene sets its solver or none fits. */
double f3r_choice_solver_cost(const choice_run* run, const f3r_accuracy_choice* c,
                              const int modes[3], double model_error, int corrected);
/* The largest model error that still leaves the static correction's solver a measured relation
 * (a tenth of the budget, as f3r_choice_solver_cost keeps there) beside exact kinematics' error;
 * 0 where the scene sets its solver. */
double f3r_choice_wide_model_target(const choice_run* run, const f3r_accuracy_choice* c);
/* The basis (accuracy_basis.c): the same search with the static shapes on the correctable links,
 * the cheaper basis kept in run->ms and run->s; the paper's modes' search within
 * run->deferred_target, if it waited; whether it may wait for the corrected one. */
f3r_status f3r_choice_compare_bases(choice_run* run, f3r_accuracy_choice* c, f3r_error* err);
f3r_status f3r_choice_resume_plain_search(choice_run* run, f3r_accuracy_choice* c, f3r_error* err);
/* Whether the paper's modes fit target at a uniform r = 1 .. PLAIN_FIRST_MOST, each against its
 * own reference: the first part of their search, which never waits. */
f3r_status f3r_choice_plain_first_part(choice_run* run, double target, int* fits, f3r_error* err);
int f3r_choice_plain_search_may_wait(const choice_run* run);

/* Appends printf-style text to text (size bytes in all), never past its end. */
void f3r_accuracy_append(char* text, size_t size, const char* fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* The summary's lines, each appended to c->summary (and the estimate's to c->brief). */
void f3r_summarise_modes(const choice_run* run, f3r_accuracy_choice* c);
void f3r_summarise_kinematics(const choice_run* run, f3r_accuracy_choice* c);
void f3r_summarise_relation(const choice_run* run, f3r_accuracy_choice* c, const solver_pick* p);
void f3r_summarise_estimate(const choice_run* run, f3r_accuracy_choice* c);

#endif

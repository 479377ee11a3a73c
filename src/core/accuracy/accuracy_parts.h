/* The accuracy layer's private parts, one header: the knob's stages (accuracy.c chooses;
 * accuracy_search.c searches the mode counts on the linearised model; accuracy_pilot.c checks
 * them with short nonlinear runs; accuracy_solver.c the measured solver relations), and what the
 * stages of one choice share with its report (accuracy_report.c). Internal to the core. */
#ifndef F3R_ACCURACY_PARTS_H
#define F3R_ACCURACY_PARTS_H

#include "flex3rpr/accuracy.h"
#include "flex3rpr/linear.h"
#include "flex3rpr/sim.h"
#include "linear_parts.h"

#define F3R_PILOT_SHARE 0.1 /* of the duration: the window a pilot runs over */
#define F3R_PATH_MEMO 12    /* linear paths the mode search keeps */

static inline int f3r_is_flexible(const f3r_scene* s, int i) {
  return s->links[i].model != F3R_LINK_RIGID;
}

/* The scene with fixed mode counts, no accuracy request: a model the caller must destroy. */
f3r_status f3r_model_with_modes(const f3r_scene* base, const int modes[3], int exact_kinematics,
                                f3r_model** model, f3r_error* err);
/* Largest end-effector distance between two pose paths (3 values a sample) over count samples. */
double f3r_max_distance(const double* a, const double* b, int count);

/* What the mode search shares: the sampling, the links chosen, their least counts (the initial
 * state's highest mode), the order of the linear path (2 near the initial pose, where the
 * second-order correction holds; 1 where the path leaves it and the pilot checks instead) and the
 * current reference path. */
typedef struct {
  double dt;
  int count;
  unsigned chosen;
  int low[3];
  int fixed[3];       /* the modes of the links not chosen */
  unsigned corrected; /* the links whose basis adds the static shapes (the scene's flags) */
  unsigned mixed;     /* of those, the links whose correction is one mixed shape (shape_mix) */
  int most[3];        /* the most modes link i may take: F3R_MAX_MODES less its shapes */
  int order;
  int ref_r;       /* the uniform count the reference in ref has on the chosen links, 0: none */
  double* ref;     /* 3 count */
  double* path;    /* 3 count, scratch */
  double extent;   /* m: largest distance of the linearised end effector from its start */
  double rotation; /* rad: largest linearised platform rotation from its start */
  int far;         /* the first- or second-order path leaves the initial pose far */
  int at_rest;
  int evaluations; /* linear models built and solved (a path found in the memo is not one) */
  double* inputs;  /* count F3R_RIGID_FORCES: the scene's inputs at the sampling, or NULL until a
                    * path needs them (every model of the scene samples the same values) */
  /* The paths computed so far, by mode counts and order, at the current sampling: the search runs
   * again after the pilot, and the pilot's pair needs paths the search has made. */
  struct {
    int modes[3];
    int order;
    unsigned corrected, mixed;
    double* pose; /* 3 count */
  } memo[F3R_PATH_MEMO];
  int memo_used, memo_next;
} f3r_mode_search;

/* The linearised end-effector path (x, y, phi a sample) at the search's sampling; order 1, or 2
 * with the second-order correction. */
f3r_status f3r_linear_path(const f3r_scene* s, f3r_mode_search* ms, const int modes[3], int order,
                           double* pose, f3r_error* err);
/* Sampling, links and the order of the estimate for a scene; f3r_mode_search_free after. `same`
 * (or NULL): a search of a scene with the same inputs, duration and output step, whose sampled
 * inputs it starts from instead of sampling them again. */
f3r_status f3r_mode_search_init(const f3r_scene* s, unsigned chosen, const f3r_mode_search* same,
                                f3r_mode_search* ms, f3r_error* err);
/* The linear path (order 1 or 2) at modes, at the search's sampling, from the memo or computed
 * into it: pose gets 3 count values. */
f3r_status f3r_mode_search_path(const f3r_scene* s, f3r_mode_search* ms, const int modes[3],
                                int order, double* pose, f3r_error* err);
/* The fewest modes whose linear path stays within target of its reference (estimate: that
 * distance). */
f3r_status f3r_mode_search_run(const f3r_scene* s, f3r_mode_search* ms, double target, int modes[3],
                               double* estimate, f3r_error* err);
void f3r_mode_search_free(f3r_mode_search* ms);
/* Whether r modes on every chosen link (r <= 3) stay within target of their own reference, as
 * f3r_mode_search_run tests r = 1, 2, 3: *fits 1 or 0. */
f3r_status f3r_mode_search_fits(const f3r_scene* s, f3r_mode_search* ms, int r, double target,
                                int* fits, f3r_error* err);
/* The least mode counts the search may give: one mode, or the initial state's highest, on each
 * chosen link; the other links keep theirs. */
void f3r_mode_search_least(const f3r_mode_search* ms, int modes[3]);
/* r on the chosen links (at least their initial state's, at most their room), the scene's counts
 * on the others: the counts the search tries at r. */
void f3r_mode_search_uniform(const f3r_mode_search* ms, int r, int modes[3]);

/* The links of s with static_correction and shape_mix: fit (bit i). */
unsigned f3r_shape_mix_open(const f3r_scene* s);
/* Fits the links in the mask `links` on scene `at` (f3r_shape_mix_fit, at its counts) and makes
 * each of them one mixed shape of that ratio in `out` (which may be `at`); the ratios into mix
 * (may be NULL). */
f3r_status f3r_shape_mix_set_fitted(const f3r_scene* at, unsigned links, f3r_scene* out,
                                    double* mix, f3r_error* err);
/* 1 when the search found counts within its target (0: the chosen links are at their most). */
int f3r_mode_search_found(const f3r_mode_search* ms, const int modes[3]);
/* The relative CPU cost of a run at modes: sqrt(highest linearised frequency) times the
 * coordinates. IDA's steps grow as the square root of the highest frequency and a step's cost
 * with the coordinates (docs/benchmarks/practical_tolerances.md: 105 000, 142 000 and 262 000
 * steps for 6.8, 16 and 49 kHz; 0.15, 0.26 and 0.67 s against 1 : 2.0 : 5.0 here). */
f3r_status f3r_basis_cost(const f3r_scene* s, const int modes[3], double* cost, f3r_error* err);
/* The effect of exact kinematics on the end-effector path at the given modes, to first order:
 * the linear response to its added forces along the first-order linear path, at the search's
 * sampling (linear.h: f3r_linear_difference_response). */
f3r_status f3r_linear_kinematics(const f3r_scene* s, const f3r_mode_search* ms, const int modes[3],
                                 double* effect, f3r_error* err);

/* The nonlinear pilot: short runs over the first F3R_PILOT_SHARE of the duration, at the least
 * mode counts (where the mode-count differences stand far above the pilot's own solver error),
 * with a tolerance whose measured error is a tenth of the model's share. */
typedef struct {
  int count;    /* samples in the window */
  double grow;  /* duration / window */
  double noise; /* m: the pilot's own solver error */
  f3r_solver_settings tight;
  int modes[3];
  int exact_kinematics; /* the runs' own setting, the choice's (f3r_pilot_kinematics turns it on) */
  double* a;            /* the path at modes, tight */
  double* b;            /* scratch */
} f3r_pilot;

/* The measured cost (a solver relation's) of the tight pilot's solver for kind, resolution and
 * capped as f3r_pilot_start takes them. */
double f3r_pilot_cost(const char* kind, double resolution, int capped);
/* Runs the tight pilot at modes and exact_kinematics over the window (kind: the solver relations'
 * kind; resolution: the error the pilot's own solver may have; capped: never looser than rtol
 * 1e-6). f3r_pilot_free after, whatever it returns. */
f3r_status f3r_pilot_start(const f3r_scene* s, const f3r_mode_search* ms, const int modes[3],
                           int exact_kinematics, const char* kind, double resolution, int capped,
                           f3r_pilot* p, f3r_error* err);
/* The nonlinear difference of the pilot's modes and one more on each chosen link, carried to the
 * whole run, and the linear one over the whole run. */
f3r_status f3r_pilot_pair(const f3r_scene* s, f3r_mode_search* ms, f3r_pilot* p, double* nonlinear,
                          double* linear, f3r_error* err);
/* The effect of turning exact kinematics on at the pilot's modes (a pilot run without it),
 * carried to the whole run. */
f3r_status f3r_pilot_kinematics(const f3r_scene* s, const f3r_mode_search* ms, f3r_pilot* p,
                                double* effect, f3r_error* err);
/* A solver's error at the pilot's modes against the tight pilot, carried to the whole run. */
f3r_status f3r_pilot_solver(const f3r_scene* s, const f3r_mode_search* ms, f3r_pilot* p,
                            const f3r_solver_settings* solver, double* error, f3r_error* err);
void f3r_pilot_free(f3r_pilot* p);

/* ---- What the stages of one accuracy choice share (accuracy.c), and the report they write
 * (accuracy_report.c): the summary's prose lives apart from the choosing. ---- */

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

/* The accuracy knob's parts (accuracy.c chooses; accuracy_search.c searches the mode counts on
 * the linearised model; accuracy_pilot.c checks them with short nonlinear runs). Internal to
 * the core. */
#ifndef F3R_ACCURACY_PARTS_H
#define F3R_ACCURACY_PARTS_H

#include "flex3rpr/accuracy.h"
#include "flex3rpr/linear.h"
#include "flex3rpr/sim.h"

#define F3R_PILOT_SHARE 0.1 /* of the duration: the window a pilot runs over */
#define F3R_PATH_MEMO 12    /* linear paths the mode search keeps */

static inline int f3r_is_flexible(const f3r_scene* s, int i) {
  return s->links[i].model != F3R_LINK_RIGID;
}

/* The scene with fixed mode counts, no accuracy request: a model the caller must destroy. */
f3r_status f3r_model_with_modes(const f3r_scene* base, const int modes[3], int exact_kinematics,
                                f3r_model** model, f3r_error* err);
/* The scene's inputs (through the actuator lag) at t_k = k dt, k < count, into u
 * (F3R_RIGID_FORCES a sample): what f3r_linear_response samples (linear_model.c). */
void f3r_linear_sample_inputs(const f3r_model* model, double dt, int count, double* u);
/* f3r_linear_response (other NULL) or f3r_linear_difference_response (order 1) on inputs sampled
 * by f3r_linear_sample_inputs at the same dt and count (inputs may be NULL: sampled here). */
f3r_status f3r_linear_response_sampled(const f3r_linear_model* lin, const f3r_model* model,
                                       const f3r_model* other, const double* inputs, double dt,
                                       int count, int order, double* pose, int* unreachable,
                                       f3r_error* err);
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

/* L = the Cholesky factor of the linear model's mass matrix (n x n, linear_model.c); who names
 * the caller in the error when the matrix is not positive definite. */
f3r_status f3r_linear_mass_factor(const f3r_linear_model* lin, double* L, const char* who,
                                  f3r_error* err);

#endif

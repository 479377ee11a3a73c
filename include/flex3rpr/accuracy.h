/* The accuracy knob: from a requested end-effector accuracy (m) to the cheapest mode counts,
 * exact kinematics, formulation, integrator and tolerance that deliver it. Settings the scene
 * file gives itself (f3r_scene.explicit_settings) are kept; the knob chooses the rest.
 *
 * Total error = model error + kinematics error + solver error, each given a share of the request:
 *  - model error: the end-effector path of the linearised model (linear.h) with r modes against
 *    the same with F3R_MAX_MODES on every link being chosen, over the scene's own inputs,
 *    duration and initial state; r is raised uniformly until it fits, then trimmed per link.
 *    Where the scene leaves links[i].static_correction open on a fixed-free link, the same search
 *    runs with the static shapes added (against the corrected basis with more modes), and the
 *    cheaper basis that fits is kept (f3r_basis_cost: steps from the highest frequency);
 *  - pilot check: when the linear path leaves the initial pose far, short nonlinear runs at the
 *    least mode counts and one more measure what the linearisation cannot, unless the linear
 *    estimate lies far below its share; with end stops the knob takes 20 modes instead;
 *  - kinematics error: 0, as exact kinematics is on wherever the scene leaves it open (it costs no
 *    measurable CPU time); where the scene turns it off, its estimated effect: a linear estimate
 *    of its added forces along the linear path, and a pilot run with it on unless that is
 *    negligible;
 *  - solver error: the benchmark's measured relation of error to tolerance (solver_table.c).
 * modes: auto without an accuracy request asks the linear estimate for auto_tolerance of the
 * path's extent. */
#ifndef FLEX3RPR_ACCURACY_H
#define FLEX3RPR_ACCURACY_H

#include "flex3rpr/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Shares of the request given to each part of the error. */
#define F3R_ACCURACY_MODEL_SHARE 0.5
#define F3R_ACCURACY_KINEMATICS_SHARE 0.2
#define F3R_ACCURACY_SOLVER_SHARE 0.25

typedef struct {
  double request;           /* m; 0 when only modes: auto asked */
  int modes[3];             /* per link; 0 for rigid links */
  int static_correction[3]; /* 1: link i's basis adds its static shapes to its modes */
  double shape_mix[3];      /* with it, the one mixed shape's load ratio (links[i].shape_mix);
                             * NaN: the pair of shapes, or the scene's own fit, resolved later */
  int exact_kinematics;
  f3r_formulation formulation;
  f3r_integrator integrator;
  char table[48]; /* the Butcher table for erk and dirk, "" for the default */
  double rtol, atol;
  double model_error;       /* m, estimated error of the mode counts */
  double kinematics_effect; /* m, estimated effect of exact kinematics on the path; estimated only
                           * where the scene turns it off (0 otherwise) */
  double
      kinematics_error; /* m, the part of it left in the run: the effect when it is off, else 0 */
  double kinematics_linear; /* m, the effect's linear estimate (0 when not computed) */
  double solver_error;      /* m, the measured relation's error at rtol */
  double extent;            /* m, largest distance of the linear end-effector path from its start */
  int pilot;                /* 1 when nonlinear pilot runs checked the estimate */
  double excitation;        /* N: the leg-force steps a commanded choice was sized for (the scene's
                             * accuracy.excitation or limits.force, halved while the pilot runs
                             * could not follow them); 0 when the scene's own inputs decided */
  double pilot_ratio;       /* nonlinear over linear mode-count difference in the pilot window */
  int linear_evaluations;   /* linear models built and solved */
  double estimated_error;   /* m: model + kinematics + solver error; 0 when nothing was chosen */
  int request_met;          /* 1 when estimated_error <= request; 0 names the largest part in the
                           * summary and the brief (a scene's own settings, or what no choice
                           * within F3R_MAX_MODES and the measured solvers reaches) */
  /* The measurement (f3r_accuracy_check_scene), filled in by whoever runs the check (the CLI):
   * the run's end-effector distance from the check's path at the output times. */
  int verified;          /* 1: measured_error is a measurement; 0: estimated_error only */
  double measured_error; /* m; NaN where not measured */
  int configurations;    /* runs for it: each configuration tried and its check; 0 unmeasured */
  char summary[2048];    /* the choice and why, one line per decision */
  char brief[256];       /* the same in one line, for a status message */
} f3r_accuracy_choice;

/* Chooses for `request` (m, > 0). The scene's explicit settings are kept and reported.
 * commanded: 1 when a caller will hold new forces every output period (the node), so that the
 * solver relation measured with such restarts applies. */
f3r_status f3r_accuracy_choose(const f3r_scene* scene, double request, int commanded,
                               f3r_accuracy_choice* choice, f3r_error* err);

/* Writes a choice into the scene (modes, exact kinematics, solver), where the scene left it open. */
void f3r_accuracy_apply(const f3r_accuracy_choice* choice, f3r_scene* scene);

/* The load ratio (links[i].shape_mix, scene.h) of each fixed-free link in the mask `links`
 * (bit i), with static_correction, that the mechanism's slowest modes put on it: the linearised
 * model with the link's two static shapes, its lowest group of modes in which the link takes
 * part, the principal direction of the link's two shape coordinates over it. Its mode counts are
 * the scene's. mix[i] is 0 for links outside the mask and where the basis keeps one shape. */
f3r_status f3r_shape_mix_fit(const f3r_scene* scene, unsigned links, double mix[3], f3r_error* err);

/* Resolves a scene for a run: with scene->accuracy > 0, chooses and applies; otherwise resolves
 * links with modes: auto by the linear estimate alone. Then fits links with shape_mix: fit
 * (f3r_shape_mix_fit, at the mode counts chosen) and notes the values in the summary. choice may
 * be NULL. */
f3r_status f3r_accuracy_resolve(f3r_scene* scene, int commanded, f3r_accuracy_choice* choice,
                                f3r_error* err);

/* Mode counts for the links in `chosen` (bit i for link i) so that the linear end-effector path
 * stays within `target` (m) of the path with F3R_MAX_MODES on those links; the other links keep
 * scene->links[i].modes. target <= 0 asks for -target times the path's extent. */
f3r_status f3r_accuracy_modes(const f3r_scene* scene, unsigned chosen, double target, int modes[3],
                              double* estimate, double* extent, int* evaluations, f3r_error* err);

/* A run meets its request when its measured error is within this share of it: the check carries
 * an error of its own, and on the held-out validation suite the measurement read as low as 0.70
 * of the true error (docs/benchmarks/accuracy_validation.md). */
#define F3R_CHECK_MARGIN 0.7

/* The smallest rtol a check takes: below it IDA's steps gain nothing in double precision. */
#define F3R_CHECK_RTOL_FLOOR 1e-11

/* The configuration that measures a run of `run` (a resolved scene: no open modes): every
 * flexible link's basis richer (a fixed-free link one more mode and the static shapes' pair, a
 * fixed-pinned one two more modes; at most F3R_MAX_MODES functions, so a fixed-free link at 20
 * modes is checked on 18 and the pair), exact kinematics on, ERK with the dormand_prince_8_5
 * table (IDA at BDF order 5 on the dae formulation) and f3r_accuracy_check_rtol. With open_only,
 * what the scene fixed itself (explicit_settings, the BDF order) stays: the next configuration of
 * a run that misses. Returns 1 when *check differs from *run. *check is a view sharing run's
 * tables. */
int f3r_accuracy_check_scene(const f3r_scene* run, int open_only, f3r_scene* check);

/* The check's tolerance: a tenth of the run's, at most the request's value in metres (<= 0: no
 * request), at least F3R_CHECK_RTOL_FLOOR. */
double f3r_accuracy_check_rtol(double run_rtol, double request);

/* The largest distance between two end-effector paths, (x, y) pairs at the same count times. */
double f3r_path_distance(const double* a, const double* b, int count);

/* A measured point of the work-precision relation (solver_table.c, written by bench/work_precision). */
typedef struct {
  const char* kind; /* "flexible", "rigid" (all links rigid), "commanded" (held commands) */
  f3r_formulation formulation;
  f3r_integrator integrator;
  const char* table; /* Butcher table, "" for the default or for IDA */
  double rtol, atol; /* the benchmark's sweep sets atol = 1e-2 rtol (m, m/s) */
  double error;      /* m: the largest end-effector error over the benchmark scenes */
  double cost;       /* median over those scenes of CPU time / that of minimal IDA at 1e-6 */
  int scenes;        /* how many scenes were measured */
} f3r_solver_relation;

extern const f3r_solver_relation f3r_solver_relations[];
extern const int f3r_solver_relation_count;
extern const char f3r_solver_relations_source[]; /* machine, date and commit of the measurement */

#ifdef __cplusplus
}
#endif
#endif

/* A scene's whole run measured against its check, with escalation: the run of the knob's choice
 * and the run of its check configuration (f3r_accuracy_check_scene), the largest end-effector
 * distance between their paths at the output times; where that misses the request, the next
 * configuration (the check's, within what the scene fixes) runs and is checked in turn, up to
 * accuracy.escalations, or until the measured error stops shrinking or the cost passes ten times
 * the first configuration's. The configuration kept is the one that met the request, else the
 * one measured closest: its measured error is the error of the path a shell writes.
 *
 * The runs themselves are the shell's (its outputs, files and summary): the sequence calls back
 * to run each configuration and hand over its path and cost. Used by the CLI (flex3rpr_sim);
 * a closed loop measures as it goes instead (closed_loop_check.h). */
#ifndef FLEX3RPR_MEASURED_RUN_H
#define FLEX3RPR_MEASURED_RUN_H

#include "flex3rpr/scene.h"
#include "flex3rpr/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Configurations a measured run may try: each escalation and each check. */
#define F3R_MEASURED_MAX_CONFIGS (2 * (F3R_ACCURACY_MAX_ESCALATIONS + 1))
/* An answer costs at most this many times its first configuration's run and check. */
#define F3R_ESCALATION_COST_LIMIT 10.0
/* A configuration whose measured error is not below this fraction of the one before it has not
 * converged (impacts are the usual cause), and richer ones would only cost more. */
#define F3R_ESCALATION_SHRINK 0.5

/* What the sequence weighs of one configuration's run. */
typedef struct {
  double cpu;          /* s of process CPU time */
  long impacts;        /* end-stop impacts */
  double first_impact; /* s: the first one's time */
} f3r_run_cost;

/* Runs configuration k of `scene` over its duration at its output step; with keep, its outputs
 * are the ones the shell would write. Fills path with the end-effector's (x, y) at every output
 * (t = 0 first: duration / output_step + 1 pairs) and cost. F3R_OK, or the run's failure (the
 * shell reports it; a richer configuration may not fail). The scene is a view of the measured
 * scene's tables, valid until f3r_measured_run returns. */
typedef struct {
  void* context;
  f3r_status (*run)(void* context, int k, const f3r_scene* scene, int keep, double* path,
                    f3r_run_cost* cost);
} f3r_config_runner;

typedef struct {
  int count;    /* configurations run: each run and each check */
  int accepted; /* the one kept; -1 when every run failed */
  f3r_scene scenes[F3R_MEASURED_MAX_CONFIGS];
  double measured[F3R_MEASURED_MAX_CONFIGS]; /* m; NaN for a check, or where not measured */
  f3r_run_cost costs[F3R_MEASURED_MAX_CONFIGS];
  int failed[F3R_MEASURED_MAX_CONFIGS];
  double measured_error; /* the kept configuration's (NaN: not measured) */
  int request_met;       /* measured_error within F3R_CHECK_MARGIN of the request */
  double check_cpu;      /* s of every run but the kept one */
  char attempts[1024];   /* one line a configuration: what it measured against what */
  char stopped[256];     /* why escalation stopped before its count, or "" */
} f3r_measured_run;

/* The sequence for `scene` (resolved, with its request); keep: the shell writes the kept run's
 * outputs, so a configuration that ran as a check runs again to keep them. F3R_ERR_MEMORY
 * without memory for the paths; otherwise F3R_OK, with result->accepted < 0 when every run
 * failed. */
f3r_status f3r_measured_run_sequence(const f3r_scene* scene, int keep,
                                     const f3r_config_runner* runner, f3r_measured_run* result,
                                     f3r_error* err);

/* A configuration in one line: each link's modes + static shapes ("1+2s", "-" for rigid), the
 * exact kinematics, the integrator and its tolerance. */
void f3r_describe_config(const f3r_scene* scene, char* text, size_t size);

#ifdef __cplusplus
}
#endif
#endif

/* What a run of flex3rpr_sim measures, and its JSON summary (--summary-json): the human
 * summary's numbers, units in the key names, with the error when the run fails. */
#ifndef FLEX3RPR_CLI_RUN_REPORT_H
#define FLEX3RPR_CLI_RUN_REPORT_H

#include "cli_options.h"
#include "flex3rpr/accuracy.h"
#include "flex3rpr/model.h"
#include "flex3rpr/measured_run.h"
#include "flex3rpr/scene.h"
#include "flex3rpr/sim.h"

#include <stdio.h>

/* What a run measures for its summary. */
typedef struct {
  double max_constraint, max_energy_error, max_energy;
  double max_deflection, max_tip;        /* |w| over the beam stations, and at the tips */
  double cpu_total;                      /* process CPU time over the run */
  double wall_total;                     /* monotonic (wall) time over the run */
  double wall_integrating, wall_outputs; /* its split, also wall time (flex3rpr_sim.c) */
  int end_stops;                         /* the scene's end stops are on */
  long impacts;                          /* end-stop impacts (lockings included) */
  double first_impact;                   /* s: the first impact's time, at the output step where
                                          * several came at once; 0 with none (impacts 0) */
  double max_stop_force[3];              /* largest |stop force| on each leg (N) */
  double final_stop_force[3];            /* the stop forces at the end (N; + pushes outwards) */
} run_stats;

/* What a simulation leaves for the JSON summary. */
typedef struct {
  int ran;
  double t, x, y, phi;
  long steps, residual_evals, jacobian_evals;
  run_stats stats;
  double check_cpu;   /* s: the accuracy check's runs (every configuration but the written one) */
  int configurations; /* configurations run for an accuracy request's measurement; 0: none */
} run_report;

/* The real-time factors the summaries print, each named by its clock: the process CPU clock over
 * the whole run (steady under load), and the wall clock over the integration alone and with the
 * outputs (what a user waiting for the run sees). */
typedef struct {
  double cpu, wall_integration, wall;
} real_time_factors;

/* What the JSON summary is written from; NULL where a failure left it out. */
typedef struct {
  const f3r_scene* scene;
  const f3r_model* model;            /* NULL: the scene did not load or build */
  const f3r_accuracy_choice* choice; /* NULL: not resolved */
  double choose_cpu;                 /* s, the accuracy knob's CPU time */
  const run_report* run;             /* NULL or !ran: no simulation */
} summary_parts;

/* The integrator as the summaries name it. */
const char* cli_integrator_text(const cli_options* o, const f3r_scene* scene);
/* Simulated time t over each clock's time. */
real_time_factors cli_real_time_factor(double t, const run_stats* r);
/* The largest energy-balance error over the largest T + V (0 when T + V stayed 0). */
double cli_energy_relative(const run_stats* r);
/* 1 when the run's energy balance error passes F3R_ENERGY_GUARD of its largest T + V. */
int cli_energy_guard(const run_stats* r);
/* The whole summary into path ("-": stdout); returns rc, or 1 when the file cannot be written. */
int cli_write_summary(const char* path, const cli_options* o, const summary_parts* p, int rc);

/* Process CPU time in s, at nanosecond resolution (clock() has microsecond steps). */
double cli_cpu_seconds(void);
/* Monotonic (wall) time in s, read through the vDSO in about 20 ns. */
double cli_monotonic_seconds(void);
/* The basis functions of every link at its beam_points stations (beam_points <= 101). */
void cli_eval_mode_shapes(const f3r_model* model, int beam_points,
                          double shapes[3][101][F3R_MAX_MODES]);
/* The summary's maxima, after one output. */
void cli_track_maxima(run_stats* r, const f3r_model* model, int beam_points,
                      double shapes[3][101][F3R_MAX_MODES], const f3r_outputs* out);
/* The human summary of a run into human. */
void cli_print_summary(FILE* human, const cli_options* o, const f3r_scene* scene,
                       const f3r_model* model, const f3r_outputs* out, const run_stats* r);
/* The final state and the counts of a run, for the JSON summary. */
void cli_keep_report(const f3r_outputs* out, const run_stats* stats, run_report* report);
/* The accuracy knob's choice, and a warning where its estimate misses the request. */
void cli_report_choice(FILE* human, const cli_options* o, const f3r_scene* scene,
                       const f3r_accuracy_choice* choice, double choose_cpu);
/* The measurement's lines, and the warning of a request not met. */
void cli_report_measurement(FILE* human, const cli_options* o, const f3r_accuracy_choice* choice,
                            const f3r_measured_run* v, const run_stats* written);

#endif

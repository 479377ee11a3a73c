/* flex3rpr_sim: runs a scene headless, writes a CSV of the trajectory and prints a summary.
 *   flex3rpr_sim SCENE.yaml [--out FILE.csv] [--formulation dae|minimal] [--rtol R] [--atol A]
 *                [--output-step DT] [--duration T] [--fd-jacobian] [--dense-linear-solver]
 *                [--exact-kinematics] [--ida | --erk | --dirk] [--table NAME]
 *                [--accuracy METRES] [--linear-path FILE.csv] [--set FIELD=VALUE ...] ...
 *   flex3rpr_sim --modal SCENE.yaml
 *   flex3rpr_sim SCENE.yaml --linearise FILE.mat [--set ...]   (state-space export, linear.h)
 *   flex3rpr_sim --geometry SCENE.yaml   (JSON for nodes/make_urdf.py)
 *   flex3rpr_sim --check SCENE.yaml [--set ...]   (loads and builds the model only)
 * --summary-json FILE (or - for stdout, the human summary then on stderr) writes the summary's
 * numbers as JSON, units in the key names, with the error when the run fails (run_report.c). */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <sundials/sundials_config.h>

#include "flex3rpr/accuracy.h"
#include "flex3rpr/beam_modes.h"
#include "flex3rpr/measured_run.h"
#include "flex3rpr/session.h"
#include "flex3rpr/sim.h"
#include "cli_options.h"
#include "flex3rpr/csv_number.h"
#include "sensor_columns.h"
#include "model_reports.h"
#include "flex3rpr/output_columns.h"
#include "cli_overrides.h"
#include "csv_rows.h"
#include "hold_table.h"
#include "run_report.h"

/* Where the human summary goes: stdout, or stderr when the JSON takes stdout. */
static FILE* human;

/* The exit code of a run whose accuracy request the measurement found unmet (the path written is
 * the closest measured): 1 is a failure, 2 a usage error. */
#define F3R_EXIT_ACCURACY_NOT_MET 3

/* The scene (file, options, overrides) opened as the core's session, as the node and Python
 * open theirs: the load, the accuracy knob's choice and the model. NULL with a message when any
 * of them fails. */
static f3r_session* open_session(const cli_options* o) {
  f3r_error err = {0};
  override_list overrides;
  f3r_session* session = NULL;
  /* Minimal is the default formulation, and an override would make it an explicit setting, which
   * the accuracy knob keeps: --erk and --dirk force it only when the scene does not load without
   * (a dae from the file or --formulation, which is explicit already). */
  for (int force = 0; force < 2 && !session; ++force) {
    if (force && !cli_integrator_minimal_only(o)) break;
    cli_build_overrides(o, force, &overrides);
    /* a --hold table is a controller's commands, held over output steps: the knob chooses as for
     * one (the commanded relation, accuracy.excitation), as the node and Python do */
    const f3r_session_options options = {.accuracy = o->accuracy,
                                         .overrides = overrides.all,
                                         .override_count = overrides.n_all,
                                         .commanded = o->n_holds > 0,
                                         .model_only = 1};
    if (f3r_session_open(o->scene_path, &options, &session, &err) == F3R_OK) return session;
    if (err.code != F3R_ERR_SCENE) break; /* the load passed: the choice or the model failed */
  }
  if (err.code == F3R_ERR_SCENE)
    cli_report_load_error(o, &overrides, &err);
  else
    cli_fail(f3r_status_name(err.code), "%s: %s", o->scene_path, err.message);
  return NULL;
}

/* Outputs after t = 0 over the scene's duration. */
static long output_count(const f3r_scene* scene) {
  return (long)llround(scene->duration / scene->output_step);
}

/* Advances to the scene's duration output step by output step, writing rows to csv (when not
 * NULL) and the end-effector's (x, y) at every output to path (when not NULL; t = 0 first);
 * returns 1 when the simulation failed (reported), 0 otherwise. */
static int run_outputs(const cli_options* o, const f3r_scene* scene, const f3r_model* model,
                       f3r_sim* sim, FILE* csv, double* path, run_stats* r, f3r_sensors* sensors) {
  static double shapes[3][101][F3R_MAX_MODES]; /* mode shapes at the stations */
  cli_eval_mode_shapes(model, scene->beam_points, shapes);
  const long steps = output_count(scene);
  double held[F3R_MAX_Q] = {0};
  f3r_error err = {0};
  int rc = 0;
  if (path) {
    path[0] = f3r_sim_outputs(sim)->q[F3R_Q_X];
    path[1] = f3r_sim_outputs(sim)->q[F3R_Q_Y];
  }
  const double start = cli_cpu_seconds(), wall_start = cli_monotonic_seconds();
  for (long k = 1; k <= steps; ++k) {
    const double t = k == steps ? scene->duration : (double)k * scene->output_step;
    if (cli_apply_holds(o, scene->output_step, sim, held, &err) != F3R_OK) {
      cli_fail(f3r_status_name(err.code), "%s", err.message);
      rc = 1;
      break;
    }
    const double before = cli_monotonic_seconds();
    const f3r_status st = f3r_sim_advance(sim, t, &err);
    const double advanced = cli_monotonic_seconds();
    const f3r_outputs* out = f3r_sim_outputs(sim);
    r->wall_outputs += cli_monotonic_seconds() - advanced;
    r->wall_integrating += advanced - before;
    if (st == F3R_OK && sensors && f3r_sensors_update(sensors, out, &err) != F3R_OK) {
      cli_fail(f3r_status_name(err.code), "%s", err.message);
      rc = 1;
      break;
    }
    if (csv) cli_csv_row(csv, model, out, sensors);
    if (st != F3R_OK) {
      cli_fail(f3r_status_name(st), "%s", err.message);
      rc = 1;
      break;
    }
    if (path) {
      path[2 * k] = out->q[F3R_Q_X];
      path[2 * k + 1] = out->q[F3R_Q_Y];
    }
    if (out->impacts && !r->impacts) r->first_impact = out->impacts == 1 ? out->last_impact.t : t;
    cli_track_maxima(r, model, scene->beam_points, shapes, out);
  }
  if (csv) fflush(csv); /* the last rows' write belongs to the run's time too */
  r->cpu_total = cli_cpu_seconds() - start;
  r->wall_total = cli_monotonic_seconds() - wall_start;
  return rc;
}

/* One configuration's run as the CLI keeps it: its model, its CSV in memory (when it may be
 * written), what the summary prints and its last outputs. */
typedef struct {
  const f3r_model* model; /* the session's for configuration 0, else own */
  f3r_model* own;
  char* rows; /* the CSV, header included (open_memstream) */
  size_t rows_size;
  run_stats stats;
  f3r_outputs last;
} config_run;

/* The solver settings of a scene, with the command line's Jacobian and linear solver. */
static f3r_solver_settings cli_settings(const cli_options* o, const f3r_scene* scene) {
  f3r_solver_settings settings = f3r_solver_settings_from_scene(scene);
  settings.analytic_jacobian = !o->fd_jacobian;
  settings.dense_linear_solver = o->dense_linear_solver;
  settings.stop_at_outputs = o->stop_at_outputs;
  return settings;
}

/* The runs of a measured run (f3r_measured_run_sequence): configuration 0 on the knob's model. */
typedef struct {
  const cli_options* o;
  config_run runs[F3R_MEASURED_MAX_CONFIGS];
} config_runs;

/* The runner the core's sequence calls: configuration k's run, its CSV into memory when keep;
 * a failure is reported here. */
static f3r_status run_config(void* context, int k, const f3r_scene* scene, int keep, double* path,
                             f3r_run_cost* cost) {
  config_runs* all = context;
  const cli_options* o = all->o;
  config_run* c = &all->runs[k];
  f3r_error err = {0};
  f3r_sim* sim = NULL;
  free(c->rows);
  c->rows = NULL;
  memset(&c->stats, 0, sizeof c->stats);
  if (!c->model && f3r_model_create(scene, &c->own, &err) != F3R_OK) {
    cli_fail(f3r_status_name(err.code), "%s: the accuracy check: %s", o->scene_path, err.message);
    return err.code;
  }
  if (!c->model) c->model = c->own;
  const f3r_solver_settings settings = cli_settings(o, scene);
  if (f3r_sim_create(c->model, &settings, &sim, &err) != F3R_OK) {
    cli_fail(f3r_status_name(err.code), "%s", err.message);
    return err.code;
  }
  f3r_sensors* sensors = NULL;
  if (keep && f3r_cli_sensors_start(c->model, sim, &sensors, &err) != F3R_OK) {
    cli_fail(f3r_status_name(err.code), "%s", err.message);
    f3r_sim_destroy(sim);
    return err.code;
  }
  FILE* csv = keep ? open_memstream(&c->rows, &c->rows_size) : NULL;
  if (csv) {
    cli_csv_header(csv, c->model, sensors);
    cli_csv_row(csv, c->model, f3r_sim_outputs(sim), sensors);
  }
  const int rc = run_outputs(o, scene, c->model, sim, csv, path, &c->stats, sensors);
  f3r_sensors_destroy(sensors);
  if (csv) fclose(csv);
  c->last = *f3r_sim_outputs(sim);
  f3r_sim_destroy(sim);
  *cost = (f3r_run_cost){c->stats.cpu_total, c->stats.impacts, c->stats.first_impact};
  return rc ? F3R_ERR_SOLVER : F3R_OK;
}

/* A run for an accuracy request, measured by the core's sequence (measured_run.h): its CSV,
 * summary and report; returns the exit code (3: the request was not met). */
static int simulate_verified(const cli_options* o, f3r_scene* scene, const f3r_model** model,
                             f3r_model** owned, f3r_accuracy_choice* choice, run_report* report) {
  static config_runs all; /* large: the rows live on the heap, the runs here */
  static f3r_measured_run v;
  memset(&all, 0, sizeof all);
  all.o = o;
  all.runs[0].model = *model; /* the session's: the knob's choice */
  const f3r_config_runner runner = {&all, run_config};
  f3r_error err = {0};
  int rc = 1;
  if (f3r_measured_run_sequence(scene, o->out_path != NULL, &runner, &v, &err) != F3R_OK)
    cli_fail(f3r_status_name(err.code), "%s", err.message);
  else if (v.accepted >= 0)
    rc = v.request_met ? 0 : F3R_EXIT_ACCURACY_NOT_MET;
  if (rc != 1) {
    cli_clear_failure(); /* a failed run that a richer one replaced is not the run's */
    config_run* written = &all.runs[v.accepted];
    choice->measured_error = v.measured_error;
    choice->verified = !isnan(v.measured_error);
    choice->configurations = v.count;
    choice->request_met = v.request_met;
    if (o->out_path && cli_write_rows(o->out_path, written->rows, written->rows_size)) rc = 1;
    cli_print_summary(human, o, &v.scenes[v.accepted], written->model, &written->last,
                      &written->stats);
    cli_report_measurement(human, o, choice, &v, &written->stats);
    cli_keep_report(&written->last, &written->stats, report);
    report->check_cpu = v.check_cpu;
    report->configurations = v.count;
    *scene = v.scenes[v.accepted];
    *model = written->model; /* the summary's: kept by main */
    *owned = written->own;
    written->own = NULL;
  }
  for (int k = 0; k < F3R_MEASURED_MAX_CONFIGS; ++k) {
    f3r_model_destroy(all.runs[k].own);
    free(all.runs[k].rows);
  }
  return rc;
}

/* The simulation with its CSV and summary (and what it leaves in *report); returns the exit
 * code. With an accuracy request it is measured (simulate_verified) unless accuracy.verify is
 * off. */
static int simulate(const cli_options* o, f3r_scene* scene, const f3r_model** model,
                    f3r_model** owned, f3r_accuracy_choice* choice, run_report* report) {
  if (!cli_check_holds(o, scene, *model)) return 2;
  if (scene->accuracy > 0 && scene->accuracy_verify)
    return simulate_verified(o, scene, model, owned, choice, report);
  const f3r_solver_settings settings = cli_settings(o, scene);
  f3r_error err = {0};
  f3r_sim* sim = NULL;
  if (f3r_sim_create(*model, &settings, &sim, &err) != F3R_OK) {
    cli_fail(f3r_status_name(err.code), "%s", err.message);
    return 1;
  }
  FILE* csv = NULL;
  char* csv_buffer = NULL;
  if (o->out_path) {
    csv = fopen(o->out_path, "w");
    if (!csv) {
      cli_fail("io", "cannot write %s", o->out_path);
      f3r_sim_destroy(sim);
      return 1;
    }
    /* glibc's default buffer is the file system's block (4 KB, five rows), and each write() of
     * it costs a page-cache round trip of its own; without the memory the default stays */
    if ((csv_buffer = malloc(CSV_BUFFER_BYTES)) != NULL)
      setvbuf(csv, csv_buffer, _IOFBF, CSV_BUFFER_BYTES);
  }
  f3r_sensors* sensors = NULL;
  if (csv && f3r_cli_sensors_start(*model, sim, &sensors, &err) != F3R_OK) {
    cli_fail(f3r_status_name(err.code), "%s", err.message);
    fclose(csv);
    free(csv_buffer);
    f3r_sim_destroy(sim);
    return 1;
  }
  if (csv) {
    cli_csv_header(csv, *model, sensors);
    cli_csv_row(csv, *model, f3r_sim_outputs(sim), sensors);
  }
  run_stats stats = {0};
  const int rc = run_outputs(o, scene, *model, sim, csv, NULL, &stats, sensors);
  f3r_sensors_destroy(sensors);
  if (csv) fclose(csv);
  free(csv_buffer);
  cli_print_summary(human, o, scene, *model, f3r_sim_outputs(sim), &stats);
  if (scene->accuracy > 0)
    fprintf(human, "accuracy            estimated %.3g m, not measured (accuracy.verify is off)\n",
            choice->estimated_error);
  cli_keep_report(f3r_sim_outputs(sim), &stats, report);
  f3r_sim_destroy(sim);
  return rc;
}

/* The --summary-json FILE of a command line that did not parse, if it names one. */
static const char* summary_json_arg(int argc, char** argv) {
  for (int k = 1; k + 1 < argc; ++k)
    if (!strcmp(argv[k], "--summary-json")) return argv[k + 1];
  return NULL;
}

int main(int argc, char** argv) {
  cli_options o;
  human = stdout;
  if (!cli_parse_args(argc, argv, &o)) {
    cli_usage(stderr);
    const char* path = summary_json_arg(argc, argv);
    const summary_parts none = {0};
    if (path) cli_write_summary(path, &o, &none, 2);
    return 2;
  }
  if (o.summary_json && !strcmp(o.summary_json, "-")) human = stderr;
  f3r_scene scene = f3r_default_scene(); /* a view of the session's, or the default */
  f3r_accuracy_choice choice;
  run_report report = {0};
  summary_parts parts = {.scene = &scene, .run = &report};
  f3r_session* session = open_session(&o);
  f3r_model* owned = NULL; /* the model written, where a richer configuration's */
  int rc = 1;
  if (session) {
    scene = *f3r_session_scene(session);
    choice = *f3r_session_choice(session);
    const f3r_model* model = f3r_session_model(session);
    parts.choose_cpu = f3r_session_choose_cpu(session);
    parts.model = model;
    parts.choice = &choice;
    if (o.check || o.geometry) {
      rc = f3r_cli_describe_model(human, &o, model);
    } else {
      cli_report_choice(human, &o, &scene, &choice, parts.choose_cpu);
      rc = f3r_cli_analyse(&o, model);
      if (rc < 0) rc = simulate(&o, &scene, &model, &owned, &choice, &report);
      parts.model = model;
    }
  }
  if (o.summary_json) rc = cli_write_summary(o.summary_json, &o, &parts, rc);
  f3r_model_destroy(owned);
  f3r_session_close(session);
  return rc;
}

/* flex3rpr_sim: runs a scene headless, writes a CSV of the trajectory and prints a summary.
 *   flex3rpr_sim SCENE.yaml [--out FILE.csv] [--formulation dae|minimal] [--rtol R] [--atol A]
 *                [--output-step DT] [--duration T] [--fd-jacobian] [--dense-linear-solver]
 *                [--exact-kinematics] [--ida | --erk | --dirk] [--table NAME]
 *                [--accuracy METRES] [--linear-path FILE.csv] [--set FIELD=VALUE ...] ...
 *   flex3rpr_sim --modal SCENE.yaml
 *   flex3rpr_sim SCENE.yaml --linearise FILE.mat [--set ...]   (state-space export, linear.h)
 *   flex3rpr_sim --geometry SCENE.yaml   (JSON for scripts/make_urdf.py)
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
#include "flex3rpr/session.h"
#include "flex3rpr/sim.h"
#include "cli_options.h"
#include "flex3rpr/csv_number.h"
#include "sensor_columns.h"
#include "model_reports.h"
#include "flex3rpr/output_columns.h"
#include "run_report.h"

/* Where the human summary goes: stdout, or stderr when the JSON takes stdout. */
static FILE* human;

/* bytes of the CSV's stdio buffer: about 300 rows of paper simulation 3 (800 bytes each) */
#define CSV_BUFFER_BYTES (256 * 1024)

/* The exit code of a run whose accuracy request the measurement found unmet (the path written is
 * the closest measured): 1 is a failure, 2 a usage error. */
#define F3R_EXIT_ACCURACY_NOT_MET 3

/* The columns (output_columns.h) and the significant digits each is written with, per model. */
typedef struct {
  const f3r_model* model;
  int count;
  int digits[F3R_OUTPUT_MAX_COLUMNS];
} column_digits;

static const column_digits* digits_of(const f3r_model* m) {
  static column_digits cached;
  if (cached.model != m) {
    char name[F3R_OUTPUT_NAME];
    cached.model = m;
    cached.count = f3r_output_columns(m);
    for (int k = 0; k < cached.count; ++k) cached.digits[k] = f3r_output_column_name(m, k, name);
  }
  return &cached;
}

static void write_header(FILE* f, const f3r_model* m, const f3r_sensors* sensors) {
  char name[F3R_OUTPUT_NAME];
  const int count = f3r_output_columns(m);
  for (int k = 0; k < count; ++k) {
    f3r_output_column_name(m, k, name);
    fprintf(f, "%s%s", k ? "," : "", name);
  }
  f3r_cli_sensor_header(f, sensors);
  fprintf(f, "\n");
}

/* One row, formed in a buffer and written at once (a call to stdio a number took a fifth of the
 * writing); ",x" with x as "%.*g" (csv_number.h: the same text, 6 times faster). */
static void write_row(FILE* f, const f3r_model* m, const f3r_outputs* o,
                      const f3r_sensors* sensors) {
  char row[F3R_OUTPUT_MAX_COLUMNS * (F3R_FORMAT_G_SIZE + 1) + F3R_SENSOR_ROW_SIZE];
  double values[F3R_OUTPUT_MAX_COLUMNS];
  const column_digits* digits = digits_of(m);
  f3r_output_row(m, o, values);
  char* end = row;
  for (int k = 0; k < digits->count; ++k) {
    if (k) *end++ = ',';
    end += f3r_format_g(end, values[k], digits->digits[k]);
  }
  end = f3r_cli_sensor_row(end, sensors);
  *end++ = '\n';
  fwrite(row, 1, (size_t)(end - row), f);
}

/* Process CPU time in s, at nanosecond resolution (clock() has microsecond steps). A system
 * call of about 0.5 us: read twice per run only. */
static double cpu_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Monotonic time in s, read through the vDSO in about 20 ns: it splits the run into integration
 * and outputs at every output step. With the process CPU clock there, its two system calls per
 * output were half the "integration" time of a rigid run with 1 ms outputs. On an idle machine
 * the split adds up to the CPU time (the summary prints both). */
static double monotonic_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The scene fields the options set, as overrides "FIELD=VALUE" for the loader (numbers with
 * %.17g, which round-trip): they pass the file's checks and fix what the file would, so the
 * accuracy knob keeps them. */
#define MAX_OPTION_SETS 16
typedef struct {
  char own[MAX_OPTION_SETS][96];
  const char* all[MAX_OPTION_SETS + MAX_SETS];
  int n_own, n_all;
} override_list;

static void add_number(override_list* l, const char* field, double value) {
  if (value > 0) snprintf(l->own[l->n_own++], sizeof l->own[0], "%s=%.17g", field, value);
}

/* A string as a YAML single-quoted scalar, so that the name is read as it is. */
static void add_string(override_list* l, const char* field, const char* value) {
  char* out = l->own[l->n_own++];
  size_t n = (size_t)snprintf(out, sizeof l->own[0], "%s='", field);
  for (const char* c = value; *c && n + 3 < sizeof l->own[0]; ++c) {
    if (*c == '\'') out[n++] = '\'';
    out[n++] = *c;
  }
  snprintf(out + n, sizeof l->own[0] - n, "'");
}

/* The options' overrides, then the user's --set: applied in order, so a --set wins over an
 * option (--set solver.rtol=1e-5 --rtol 1e-6 runs at 1e-5). --erk and --dirk force the minimal
 * formulation, over --formulation but not over a --set, with force_minimal only (resolve_model). */
static void build_overrides(const cli_options* o, int force_minimal, override_list* l) {
  memset(l, 0, sizeof *l);
  if (o->formulation) add_string(l, "solver.formulation", o->formulation);
  if (o->integrator_ida) add_string(l, "solver.integrator", "ida");
  if (o->integrator_erk || o->integrator_dirk) {
    add_string(l, "solver.integrator", o->integrator_erk ? "erk" : "dirk");
    if (force_minimal) add_string(l, "solver.formulation", "minimal");
  }
  if (o->table) add_string(l, "solver.table", o->table);
  add_number(l, "solver.rtol", o->rtol);
  add_number(l, "solver.atol", o->atol);
  add_number(l, "solver.max_order", o->max_order);
  add_number(l, "run.output_step", o->output_step);
  add_number(l, "run.duration", o->duration);
  add_number(l, "accuracy.escalations", o->escalations);
  if (o->no_verify) snprintf(l->own[l->n_own++], sizeof l->own[0], "%s", "accuracy.verify=false");
  if (o->exact_kinematics)
    snprintf(l->own[l->n_own++], sizeof l->own[0], "%s", "effects.exact_kinematics=true");
  for (int k = 0; k < l->n_own; ++k) l->all[l->n_all++] = l->own[k];
  for (int k = 0; k < o->n_sets; ++k) l->all[l->n_all++] = o->sets[k];
}

/* A message about an option's override ("--set solver.rtol=0.5: ...") names the scene instead,
 * as it did when the options were written into the loaded scene. */
static void report_load_error(const cli_options* o, const override_list* l, const f3r_error* err) {
  for (int k = 0; k < l->n_own; ++k) {
    char prefix[128];
    const int n = snprintf(prefix, sizeof prefix, "--set %s: ", l->own[k]);
    if (!strncmp(err->message, prefix, (size_t)n)) {
      cli_fail(f3r_status_name(err->code), "%s: %s", o->scene_path, err->message + n);
      return;
    }
  }
  cli_fail(f3r_status_name(err->code), "%s", err->message);
}

/* The scene (file, options, overrides), what the accuracy knob chose for it in *choose_cpu s,
 * and its model. 0 with a message when any of them fails. */
static int resolve_model(const cli_options* o, f3r_scene* scene, f3r_accuracy_choice* choice,
                         double* choose_cpu, f3r_model** model) {
  f3r_error err = {0};
  override_list overrides;
  /* Minimal is the default formulation, and an override would make it an explicit setting, which
   * the accuracy knob keeps: --erk and --dirk force it only when the scene does not load without
   * (a dae from the file or --formulation, which is explicit already). */
  f3r_status st = F3R_ERR_SCENE;
  for (int force = 0; force < 2 && st != F3R_OK; ++force) {
    if (force && !o->integrator_erk && !o->integrator_dirk) break;
    build_overrides(o, force, &overrides);
    const f3r_scene_options source = {
        .accuracy = o->accuracy, .overrides = overrides.all, .override_count = overrides.n_all};
    st = f3r_scene_load_with(o->scene_path, &source, scene, &err);
  }
  if (st != F3R_OK) {
    report_load_error(o, &overrides, &err);
    return 0;
  }
  const double choose_start = cpu_seconds();
  /* a --hold table is a controller's commands, held over output steps: the knob chooses as for
   * one (the commanded relation, accuracy.excitation), as the node and Python do */
  st = f3r_accuracy_resolve(scene, o->n_holds > 0, choice, &err);
  *choose_cpu = cpu_seconds() - choose_start;
  if (st == F3R_OK) st = f3r_model_create(scene, model, &err);
  if (st != F3R_OK) {
    cli_fail(f3r_status_name(st), "%s: %s", o->scene_path, err.message);
    return 0;
  }
  return 1;
}

static void report_choice(const cli_options* o, const f3r_scene* scene,
                          const f3r_accuracy_choice* choice, double choose_cpu) {
  if (choice->summary[0]) fprintf(human, "%s\n", choice->summary);
  if (scene->accuracy > 0 && !scene->accuracy_verify && !choice->request_met)
    fprintf(stderr,
            "flex3rpr_sim: warning: %s: the accuracy request %g m is not met: estimated %.3g m "
            "(see the summary)\n",
            o->scene_path, scene->accuracy, choice->estimated_error);
  if (scene->accuracy > 0)
    fprintf(human, "choice cpu time     %.6f s (%d linear models)\n", choose_cpu,
            choice->linear_evaluations);
}

/* The basis functions of every link at its beam_points stations (beam_points <= 101). */
static void eval_mode_shapes(const f3r_model* model, int beam_points,
                             double shapes[3][101][F3R_MAX_MODES]) {
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = f3r_model_link(model, i);
    for (int k = 0; k < beam_points; ++k)
      for (int j = 0; j < lp->modes; ++j)
        f3r_model_link_shape(model, i, j, (double)k / (beam_points - 1), &shapes[i][k][j], NULL);
  }
}

static void track_maxima(run_stats* r, const f3r_model* model, int beam_points,
                         double shapes[3][101][F3R_MAX_MODES], const f3r_outputs* out) {
  r->max_constraint = fmax(r->max_constraint, out->constraint_residual);
  r->max_energy_error = fmax(r->max_energy_error, out->energy_balance_error);
  r->max_energy = fmax(r->max_energy, out->kinetic_energy + out->potential_energy);
  r->end_stops = f3r_model_scene(model)->end_stops;
  r->impacts = out->impacts;
  for (int i = 0; i < 3; ++i) {
    r->max_stop_force[i] = fmax(r->max_stop_force[i], fabs(out->stop_force[i]));
    r->final_stop_force[i] = out->stop_force[i];
  }
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = f3r_model_link(model, i);
    if (!lp->modes) continue;
    r->max_tip = fmax(r->max_tip, fabs(out->tip_deflection[i]));
    for (int k = 0; k < beam_points; ++k) {
      double w = 0.0;
      for (int j = 0; j < lp->modes; ++j) w += shapes[i][k][j] * out->q[lp->eta_index + j];
      r->max_deflection = fmax(r->max_deflection, fabs(w));
    }
  }
}

/* Outputs after t = 0 over the scene's duration. */
static long output_count(const f3r_scene* scene) {
  return (long)llround(scene->duration / scene->output_step);
}

/* Held forces change only at output times, exactly as in the node. */
static f3r_status apply_holds(const cli_options* o, double output_step, f3r_sim* sim, double* held,
                              f3r_error* err) {
  int changed = 0;
  const double t_now = f3r_sim_time(sim);
  for (int h = 0; h < o->n_holds; ++h)
    if (o->holds[h].t <= t_now + 1e-12 && held[o->holds[h].index] != o->holds[h].value &&
        o->holds[h].t > t_now - 0.5 * output_step) {
      held[o->holds[h].index] = o->holds[h].value;
      changed = 1;
    }
  return changed ? f3r_sim_set_forces(sim, held, err) : F3R_OK;
}

/* Advances to the scene's duration output step by output step, writing rows to csv (when not
 * NULL) and the end-effector's (x, y) at every output to path (when not NULL; t = 0 first);
 * returns 1 when the simulation failed (reported), 0 otherwise. */
static int run_outputs(const cli_options* o, const f3r_scene* scene, const f3r_model* model,
                       f3r_sim* sim, FILE* csv, double* path, run_stats* r, f3r_sensors* sensors) {
  static double shapes[3][101][F3R_MAX_MODES]; /* mode shapes at the stations */
  eval_mode_shapes(model, scene->beam_points, shapes);
  const long steps = output_count(scene);
  double held[F3R_MAX_Q] = {0};
  f3r_error err = {0};
  int rc = 0;
  if (path) {
    path[0] = f3r_sim_outputs(sim)->q[F3R_Q_X];
    path[1] = f3r_sim_outputs(sim)->q[F3R_Q_Y];
  }
  const double start = cpu_seconds(), wall_start = monotonic_seconds();
  for (long k = 1; k <= steps; ++k) {
    const double t = k == steps ? scene->duration : (double)k * scene->output_step;
    if (apply_holds(o, scene->output_step, sim, held, &err) != F3R_OK) {
      cli_fail(f3r_status_name(err.code), "%s", err.message);
      rc = 1;
      break;
    }
    const double before = monotonic_seconds();
    const f3r_status st = f3r_sim_advance(sim, t, &err);
    const double advanced = monotonic_seconds();
    const f3r_outputs* out = f3r_sim_outputs(sim);
    r->wall_outputs += monotonic_seconds() - advanced;
    r->wall_integrating += advanced - before;
    if (st == F3R_OK && sensors && f3r_sensors_update(sensors, out, &err) != F3R_OK) {
      cli_fail(f3r_status_name(err.code), "%s", err.message);
      rc = 1;
      break;
    }
    if (csv) write_row(csv, model, out, sensors);
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
    track_maxima(r, model, scene->beam_points, shapes, out);
  }
  if (csv) fflush(csv); /* the last rows' write belongs to the run's time too */
  r->cpu_total = cpu_seconds() - start;
  r->wall_total = monotonic_seconds() - wall_start;
  return rc;
}

static void print_summary(const cli_options* o, const f3r_scene* scene, const f3r_model* model,
                          const f3r_outputs* out, const run_stats* r) {
  fprintf(human, "scene               %s\n", o->scene_path);
  fprintf(human, "formulation         %s, rtol %g, atol %g, %s\n",
          f3r_formulation_name(scene->formulation), scene->rtol, scene->atol,
          cli_integrator_text(o, scene));
  if (scene->integrator != F3R_INTEGRATOR_IDA)
    fprintf(human, "butcher table       %s\n", scene->table[0] ? scene->table : "default");
  if (scene->integrator == F3R_INTEGRATOR_IDA)
    fprintf(human, "max BDF order       %d\n", scene->max_order);
  fprintf(human, "sundials            %s, %s\n", SUNDIALS_VERSION, F3R_SUNDIALS_BUILD);
  char basis[3][96];
  for (int i = 0; i < 3; ++i) f3r_model_link_basis_name(model, i, basis[i], sizeof basis[i]);
  fprintf(human, "links               %s; %s; %s\n", basis[0], basis[1], basis[2]);
  fprintf(human, "state dimension     %d (nq %d)\n", f3r_state_size(model, scene->formulation),
          f3r_model_nq(model));
  fprintf(human, "simulated time      %.6g s\n", out->t);
  fprintf(human, "steps               %ld\n", out->stats.steps);
  fprintf(human, "residual evals      %ld\n", out->stats.residual_evals);
  fprintf(human, "jacobian evals      %ld\n", out->stats.jacobian_evals);
  fprintf(human, "cpu time            %.6f s (process CPU clock, the whole run)\n", r->cpu_total);
  fprintf(human,
          "wall time           %.6f s (monotonic clock; integration %.6f s, computing outputs %.6f "
          "s)\n",
          r->wall_total, r->wall_integrating, r->wall_outputs);
  const real_time_factors rtf = cli_real_time_factor(out->t, r);
  fprintf(human,
          "real-time factor    %.3g of cpu time (of wall time: %.3g integrating, %.3g with the "
          "outputs)\n",
          rtf.cpu, rtf.wall_integration, rtf.wall);
  fprintf(human, "max constraint res  %.3e m\n", r->max_constraint);
  fprintf(human, "energy balance err  %.3e J (%.3e of max T+V)\n", r->max_energy_error,
          cli_energy_relative(r));
  if (cli_energy_guard(r))
    fprintf(stderr,
            "flex3rpr_sim: warning: %s: the energy balance error reached %.3g of the largest "
            "T + V (the guard is %g; correct runs stay below 2.6e-2): the integrator has likely "
            "gone unstable and the path is suspect; try a tighter rtol, IDA at max BDF order 5, "
            "or another Butcher table\n",
            o->scene_path, cli_energy_relative(r), F3R_ENERGY_GUARD);
  fprintf(human,
          "max deflection      %.6e m (largest |w| at %d stations a link; at the tips %.6e m)\n",
          r->max_deflection, scene->beam_points, r->max_tip);
  fprintf(human, "final pose          x_p %.9f y_p %.9f phi_p %.9f\n", out->q[F3R_Q_X],
          out->q[F3R_Q_Y], out->q[F3R_Q_PHI]);
  if (r->end_stops)
    fprintf(human,
            "end stops           %ld impacts; stop forces at the end %.6g %.6g %.6g N (largest "
            "%.6g %.6g %.6g N)\n",
            r->impacts, r->final_stop_force[0], r->final_stop_force[1], r->final_stop_force[2],
            r->max_stop_force[0], r->max_stop_force[1], r->max_stop_force[2]);
  if (o->out_path) fprintf(human, "csv                 %s\n", o->out_path);
}

/* The final state and the counts of a run, for the JSON summary. */
static void keep_report(const f3r_outputs* out, const run_stats* stats, run_report* report) {
  report->ran = 1;
  report->t = out->t;
  report->x = out->q[F3R_Q_X];
  report->y = out->q[F3R_Q_Y];
  report->phi = out->q[F3R_Q_PHI];
  report->steps = out->stats.steps;
  report->residual_evals = out->stats.residual_evals;
  report->jacobian_evals = out->stats.jacobian_evals;
  report->stats = *stats;
}

/* One configuration's run: its scene (a view of the loaded scene's tables) and model, its CSV in
 * memory (when one is asked for), its end-effector path and what it measured. */
typedef struct {
  f3r_scene scene;
  f3r_model* model;
  char* rows; /* the CSV, header included (open_memstream) */
  size_t rows_size;
  double* path; /* (x, y) at each output, t = 0 first */
  run_stats stats;
  f3r_outputs last;
  double measured; /* m from its check's path; NaN until checked */
  int rc;
} config_run;

static void free_config_run(config_run* c) {
  f3r_model_destroy(c->model);
  free(c->rows);
  free(c->path);
  memset(c, 0, sizeof *c);
}

/* The solver settings of a scene, with the command line's Jacobian and linear solver. */
static f3r_solver_settings cli_settings(const cli_options* o, const f3r_scene* scene) {
  f3r_solver_settings settings = f3r_solver_settings_from_scene(scene);
  settings.analytic_jacobian = !o->fd_jacobian;
  settings.dense_linear_solver = o->dense_linear_solver;
  settings.stop_at_outputs = o->stop_at_outputs;
  return settings;
}

/* Runs c->scene on c->model (built here when NULL), the CSV into memory when with_csv; 0 or 1
 * with the failure reported (in c->rc as well). */
static int run_config(const cli_options* o, int with_csv, config_run* c) {
  f3r_error err = {0};
  f3r_sim* sim = NULL;
  c->measured = NAN;
  c->rc = 1;
  const long count = output_count(&c->scene) + 1;
  if (!c->model && f3r_model_create(&c->scene, &c->model, &err) != F3R_OK) {
    cli_fail(f3r_status_name(err.code), "%s: the accuracy check: %s", o->scene_path, err.message);
    return 1;
  }
  const f3r_solver_settings settings = cli_settings(o, &c->scene);
  if (!(c->path = malloc((size_t)count * 2 * sizeof(double)))) {
    cli_fail("memory", "no memory for a path of %ld outputs", count);
    return 1;
  }
  if (f3r_sim_create(c->model, &settings, &sim, &err) != F3R_OK) {
    cli_fail(f3r_status_name(err.code), "%s", err.message);
    return 1;
  }
  f3r_sensors* sensors = NULL;
  if (with_csv && f3r_cli_sensors_start(c->model, sim, &sensors, &err) != F3R_OK) {
    cli_fail(f3r_status_name(err.code), "%s", err.message);
    f3r_sim_destroy(sim);
    return 1;
  }
  FILE* csv = with_csv ? open_memstream(&c->rows, &c->rows_size) : NULL;
  if (csv) {
    write_header(csv, c->model, sensors);
    write_row(csv, c->model, f3r_sim_outputs(sim), sensors);
  }
  c->rc = run_outputs(o, &c->scene, c->model, sim, csv, c->path, &c->stats, sensors);
  f3r_sensors_destroy(sensors);
  if (csv) fclose(csv);
  c->last = *f3r_sim_outputs(sim);
  f3r_sim_destroy(sim);
  return c->rc;
}

/* A configuration in one line: each link's modes + static shapes ("1+2s", "-" for rigid), the
 * exact kinematics, the integrator and its tolerance. */
static void describe_config(const f3r_scene* s, char* text, size_t size) {
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_scene* l = &s->links[i];
    const int shapes = l->static_correction ? f3r_link_correction_functions(l) : 0;
    n += l->model == F3R_LINK_RIGID ? snprintf(text + n, size - (size_t)n, "%s-", i ? "/" : "")
         : shapes ? snprintf(text + n, size - (size_t)n, "%s%d+%ds", i ? "/" : "", l->modes, shapes)
                  : snprintf(text + n, size - (size_t)n, "%s%d", i ? "/" : "", l->modes);
  }
  snprintf(text + n, size - (size_t)n, "%s, %s%s%s rtol %g", s->exact_kinematics ? " exact" : "",
           f3r_integrator_name(s->integrator), s->table[0] ? " " : "", s->table, s->rtol);
}

/* A run measured against its check (f3r_accuracy_check_scene); where the measurement misses the
 * request, the next configuration (the check's, within what the scene fixes) runs and is checked
 * in turn, up to accuracy.escalations. The configuration written is the one that met the request,
 * else the one measured closest: the measured error is always that of the path written. The
 * check's own path is not written: its error is not measured. Returns the exit code (3: the
 * request was not met). runs[0] holds the knob's choice on entry. */
#define MAX_CONFIGS (2 * (F3R_ACCURACY_MAX_ESCALATIONS + 1))
typedef struct {
  config_run runs[MAX_CONFIGS];
  int count;
  int accepted;     /* the run written */
  double check_cpu; /* s of CPU time of every run but the written one */
  char attempts[1024];
  char stopped[256]; /* why escalation stopped before its count, or empty */
} verification;

/* An answer costs at most this many times its first configuration's run and check: an escalation
 * that would pass it stops (the impact scene ran for minutes chasing a path that does not
 * converge). */
#define ESCALATION_COST_LIMIT 10.0
/* A configuration whose measured error is not below this fraction of the one before it has not
 * converged: impacts are the usual cause (an impact's impulse excites every mode), and richer
 * configurations would only cost more. */
#define ESCALATION_SHRINK 0.5

/* Whether a measured error meets the request, with the check's margin. */
static int measured_meets(double measured, double request) {
  return measured <= F3R_CHECK_MARGIN * request; /* false when unmeasured (NaN) */
}

/* Appends one configuration's line to the attempts' text. */
static void note_attempt(verification* v, int attempt, const char* format, ...)
    __attribute__((format(printf, 3, 4)));
static void note_attempt(verification* v, int attempt, const char* format, ...) {
  size_t n = strlen(v->attempts);
  if (attempt) n += (size_t)snprintf(v->attempts + n, sizeof v->attempts - n, "\n%20s", "");
  va_list args;
  va_start(args, format);
  if (n < sizeof v->attempts) vsnprintf(v->attempts + n, sizeof v->attempts - n, format, args);
  va_end(args);
}

/* Whether escalation stops after configuration `current` (attempt > 0: `previous` came before it):
 * its measured error did not shrink, or the next configuration, run and checked, would pass
 * ESCALATION_COST_LIMIT. Says why in v->stopped. */
static int escalation_stops(verification* v, int attempt, int current, int previous) {
  const config_run* run = &v->runs[current];
  double spent = 0.0;
  for (int k = 0; k < v->count; ++k) spent += v->runs[k].stats.cpu_total;
  const double first = v->runs[0].stats.cpu_total + v->runs[v->count > 1 ? 1 : 0].stats.cpu_total;
  /* the next configuration is this one's check (run again only for a CSV), and its own check
   * about twice that (one more mode and a tenth of the tolerance: 1.5 to 2.5 times on the
   * shipped scenes) */
  const double next = 2.0 * v->runs[v->count - 1].stats.cpu_total;
  const long impacts = run->stats.impacts;
  char why[160] = "";
  if (attempt > 0 && previous >= 0 &&
      !(run->measured < ESCALATION_SHRINK * v->runs[previous].measured))
    snprintf(why, sizeof why, "the measured error did not shrink (%.3g m, then %.3g m)",
             v->runs[previous].measured, run->measured);
  else if (spent + next > ESCALATION_COST_LIMIT * first)
    snprintf(why, sizeof why,
             "the next configuration would pass %g times the first one's cost (%.3g s so far)",
             ESCALATION_COST_LIMIT, spent);
  if (!why[0]) return 0;
  int n = snprintf(v->stopped, sizeof v->stopped, "escalation stopped: %s", why);
  if (impacts && n > 0 && (size_t)n < sizeof v->stopped)
    snprintf(v->stopped + n, sizeof v->stopped - (size_t)n,
             "; %ld end-stop impacts, the first at t = %.6g s: past an impact the path need not "
             "converge in the mode count",
             impacts, run->stats.first_impact);
  return 1;
}

static int verify_runs(const cli_options* o, f3r_accuracy_choice* choice, verification* v) {
  const double request = v->runs[0].scene.accuracy;
  const int escalations = v->runs[0].scene.accuracy_escalations,
            count = (int)output_count(&v->runs[0].scene) + 1;
  int current = 0, best = -1, previous = -1;
  v->count = 1;
  for (int attempt = 0;; ++attempt) {
    config_run* run = &v->runs[current];
    char text[256], checked[128];
    describe_config(&run->scene, text, sizeof text);
    config_run* check = NULL;
    if (!run->path && run_config(o, o->out_path != NULL, run)) {
      note_attempt(v, attempt, "%s: the run failed", text); /* reported; a richer one may not */
    } else {
      check = &v->runs[v->count++];
      f3r_accuracy_check_scene(&run->scene, 0, &check->scene);
      describe_config(&check->scene, checked, sizeof checked);
      if (run_config(o, 0, check)) {
        note_attempt(v, attempt, "%s: its check %s failed", text, checked);
      } else {
        run->measured = f3r_path_distance(run->path, check->path, count);
        note_attempt(v, attempt, "%s: measured %.3g m against %s", text, run->measured, checked);
      }
    }
    if (run->rc == 0 &&
        (best < 0 || run->measured < v->runs[best].measured || isnan(v->runs[best].measured)))
      best = current;
    if (measured_meets(run->measured, request) || attempt == escalations) break;
    if (escalation_stops(v, attempt, current, previous)) break;
    previous = current;
    f3r_scene next;
    if (!f3r_accuracy_check_scene(&run->scene, 1, &next)) break; /* the scene fixes the rest */
    if (check && check->rc == 0 && !memcmp(&next, &check->scene, sizeof next) && !o->out_path) {
      current = (int)(check - v->runs); /* the check is the next configuration, and has run */
      continue;
    }
    /* the next configuration runs (again, where it was the check: with its CSV, which the
     * check's run does not format, as that took 40 % of a run with 1e-4 s outputs) */
    current = v->count++;
    v->runs[current].scene = next;
  }
  if (best < 0) return 1; /* every run failed: reported */
  v->accepted = best;
  for (int k = 0; k < v->count; ++k)
    if (k != best) v->check_cpu += v->runs[k].stats.cpu_total;
  choice->measured_error = v->runs[best].measured;
  choice->verified = !isnan(choice->measured_error);
  choice->configurations = v->count;
  choice->request_met = measured_meets(choice->measured_error, request);
  return choice->request_met ? 0 : F3R_EXIT_ACCURACY_NOT_MET;
}

/* The CSV of the run written, from memory. */
static int write_rows(const cli_options* o, const config_run* c) {
  FILE* f = fopen(o->out_path, "w");
  if (!f || fwrite(c->rows, 1, c->rows_size, f) != c->rows_size || fclose(f)) {
    cli_fail("io", "cannot write %s", o->out_path);
    return 1;
  }
  return 0;
}

/* The summary's lines on the measurement, and the warnings of a request not met. */
static void report_measurement(const cli_options* o, const f3r_accuracy_choice* choice,
                               const verification* v) {
  const double request = v->runs[0].scene.accuracy;
  const config_run* written = &v->runs[v->accepted];
  fprintf(human,
          "accuracy            measured %.3g m against a richer run (estimate %.3g m); "
          "request %g m %s (measured, within %g of it)\n",
          choice->measured_error, choice->estimated_error, request,
          choice->request_met ? "met" : "NOT met", F3R_CHECK_MARGIN);
  fprintf(human, "check cpu time      %.6f s (%.2f of the run's %.6f s; %d runs in all)\n",
          v->check_cpu, written->stats.cpu_total > 0 ? v->check_cpu / written->stats.cpu_total : 0,
          written->stats.cpu_total, v->count);
  fprintf(human, "configurations      %s\n", v->attempts);
  if (v->stopped[0]) fprintf(human, "                    %s\n", v->stopped);
  if (!choice->request_met)
    fprintf(stderr,
            "flex3rpr_sim: %s: the accuracy request %g m is not met: measured %.3g m (it must be "
            "within %g of the request) after %d runs (%s); the path written is the one measured "
            "closest%s%s%s\n",
            o->scene_path, request, choice->measured_error, F3R_CHECK_MARGIN, v->count, v->attempts,
            written->scene.accuracy_escalations ? "" : " (accuracy.escalations is 0)",
            v->stopped[0] ? "; " : "", v->stopped);
}

/* A run for an accuracy request, measured (verify_runs): its CSV, summary and report. */
static int simulate_verified(const cli_options* o, f3r_scene* scene, f3r_model** model,
                             f3r_accuracy_choice* choice, run_report* report) {
  static verification v; /* large: the paths and rows live on the heap, the runs here */
  memset(&v, 0, sizeof v);
  v.runs[0].scene = *scene;
  v.runs[0].model = *model; /* handed back below, or destroyed with the others */
  *model = NULL;
  int rc = verify_runs(o, choice, &v);
  if (rc != 1) cli_clear_failure(); /* a failed run that a richer one replaced is not the run's */
  const config_run* written = &v.runs[v.accepted];
  if (rc != 1) {
    if (o->out_path && write_rows(o, written)) rc = 1;
    print_summary(o, &written->scene, written->model, &written->last, &written->stats);
    report_measurement(o, choice, &v);
    keep_report(&written->last, &written->stats, report);
    report->check_cpu = v.check_cpu;
    report->configurations = v.count;
    *scene = written->scene;
    *model = written->model;
    v.runs[v.accepted].model = NULL;
  } else {
    *model = v.runs[0].model;
    v.runs[0].model = NULL;
  }
  for (int k = 0; k < v.count; ++k) free_config_run(&v.runs[k]);
  return rc;
}

/* The --hold table as commands from outside: the command held after each hold, checked by the
 * session's rule (flex3rpr/session.h) with the value named as every shell names it. 0 when one
 * is refused (said). */
static int check_holds(const cli_options* o, const f3r_scene* scene, const f3r_model* model) {
  const int nq = f3r_model_nq(model);
  f3r_error err = {0};
  for (int h = 0; h < o->n_holds; ++h) {
    const hold_event* e = &o->holds[h];
    if (e->index >= nq) {
      cli_fail("usage", "--hold %g:%d:%g: index %d is out of range 0..%d (nq = %d)", e->t, e->index,
               e->value, e->index, nq - 1, nq);
      return 0;
    }
    /* the command from e's time: each index at its latest hold by then (later in the list on
     * a tie, as apply_holds applies them) */
    double held[F3R_MAX_Q] = {0}, since[F3R_MAX_Q];
    for (int n = 0; n < nq; ++n) since[n] = -1.0;
    for (int k = 0; k < o->n_holds; ++k) {
      const hold_event* x = &o->holds[k];
      if (x->t <= e->t && x->t >= since[x->index]) {
        held[x->index] = x->value;
        since[x->index] = x->t;
      }
    }
    if (f3r_command_check(scene, model, held, nq, &err) != F3R_OK) {
      cli_fail(f3r_status_name(err.code), "--hold %g:%d:%g: %s", e->t, e->index, e->value,
               err.message);
      return 0;
    }
  }
  return 1;
}

/* The simulation with its CSV and summary (and what it leaves in *report); returns the exit
 * code. With an accuracy request it is measured (simulate_verified) unless accuracy.verify is
 * off. */
static int simulate(const cli_options* o, f3r_scene* scene, f3r_model** model,
                    f3r_accuracy_choice* choice, run_report* report) {
  if (!check_holds(o, scene, *model)) return 2;
  if (scene->accuracy > 0 && scene->accuracy_verify)
    return simulate_verified(o, scene, model, choice, report);
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
    write_header(csv, *model, sensors);
    write_row(csv, *model, f3r_sim_outputs(sim), sensors);
  }
  run_stats stats = {0};
  const int rc = run_outputs(o, scene, *model, sim, csv, NULL, &stats, sensors);
  f3r_sensors_destroy(sensors);
  if (csv) fclose(csv);
  free(csv_buffer);
  print_summary(o, scene, *model, f3r_sim_outputs(sim), &stats);
  if (scene->accuracy > 0)
    fprintf(human, "accuracy            estimated %.3g m, not measured (accuracy.verify is off)\n",
            choice->estimated_error);
  keep_report(f3r_sim_outputs(sim), &stats, report);
  f3r_sim_destroy(sim);
  return rc;
}

/* --check and --geometry: the model only, before the accuracy knob's report. */
static int describe_model(const cli_options* o, const f3r_model* model) {
  if (o->check) /* the scene, its overrides and the model are valid: what a sweep checks first */
    fprintf(human, "ok: %s, nq %d\n", o->scene_path, f3r_model_nq(model));
  else
    f3r_cli_print_geometry(model);
  return 0;
}

/* The analyses that replace a simulation (--linear-path, --linearise, --modal): the exit code,
 * or -1 when none was asked for. */
static int analyse(const cli_options* o, const f3r_model* model) {
  if (o->linear_path) return f3r_cli_write_linear_path(model, o->linear_path);
  if (o->linearise_path) return f3r_cli_write_state_space(model, o->linearise_path);
  if (o->modal || o->modal_csv) return f3r_cli_run_modal(model, o->modal_csv);
  return -1;
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
  f3r_scene scene = f3r_default_scene(); /* the loaded one owns tables: freed at the end */
  f3r_accuracy_choice choice;
  run_report report = {0};
  summary_parts parts = {.scene = &scene, .run = &report};
  f3r_model* model = NULL;
  int rc = 1;
  if (resolve_model(&o, &scene, &choice, &parts.choose_cpu, &model)) {
    parts.model = model;
    parts.choice = &choice;
    if (o.check || o.geometry) {
      rc = describe_model(&o, model);
    } else {
      report_choice(&o, &scene, &choice, parts.choose_cpu);
      rc = analyse(&o, model);
      if (rc < 0) rc = simulate(&o, &scene, &model, &choice, &report);
      parts.model = model;
    }
  }
  if (o.summary_json) rc = cli_write_summary(o.summary_json, &o, &parts, rc);
  f3r_model_destroy(model);
  f3r_scene_free(&scene);
  return rc;
}

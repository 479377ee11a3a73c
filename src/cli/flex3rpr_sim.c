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
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <sundials/sundials_config.h>

#include "flex3rpr/accuracy.h"
#include "flex3rpr/beam_modes.h"
#include "flex3rpr/sim.h"
#include "cli_options.h"
#include "csv_number.h"
#include "model_reports.h"
#include "run_report.h"

/* Where the human summary goes: stdout, or stderr when the JSON takes stdout. */
static FILE* human;

/* bytes of the CSV's stdio buffer: about 300 rows of paper simulation 3 (800 bytes each) */
#define CSV_BUFFER_BYTES (256 * 1024)

static void write_header(FILE* f, const f3r_model* m) {
  static const char* rigid[9] = {"rho_1",   "rho_2", "rho_3", "theta_1", "theta_2",
                                 "theta_3", "x_p",   "y_p",   "phi_p"};
  fprintf(f, "t");
  for (int pass = 0; pass < 2; ++pass) {
    const char* suffix = pass ? "_dot" : "";
    for (int n = 0; n < F3R_Q_MODAL; ++n) fprintf(f, ",%s%s", rigid[n], suffix);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < f3r_model_link(m, i)->modes; ++j)
        fprintf(f, ",eta_%d_%d%s", i + 1, j + 1, suffix);
    for (int i = 0; i < 3; ++i) fprintf(f, ",w_tip_%d%s", i + 1, suffix);
  }
  fprintf(f, ",lambda_1x,lambda_1y,lambda_2x,lambda_2y,lambda_3x,lambda_3y");
  fprintf(f, ",kinetic_energy,potential_energy,external_work,constraint_residual\n");
}

/* ",x" at end with x as "%.*g" writes it (csv_number.h: the same text, 6 times faster); returns
 * the new end. */
static char* put_number(char* end, double x, int precision) {
  *end++ = ',';
  return end + f3r_format_g(end, x, precision);
}

/* One row, formed in a buffer and written at once (a call to stdio a number took a fifth of the
 * writing). */
static void write_row(FILE* f, const f3r_model* m, const f3r_outputs* o) {
  char row[(2 * (F3R_MAX_Q + 3) + F3R_NCON + 5) * (F3R_FORMAT_G_SIZE + 1)];
  char* end = row + f3r_format_g(row, o->t, 10);
  for (int pass = 0; pass < 2; ++pass) {
    const double* x = pass ? o->v : o->q;
    for (int n = 0; n < f3r_model_nq(m); ++n) end = put_number(end, x[n], 15);
    const double* w = pass ? o->tip_deflection_rate : o->tip_deflection;
    for (int i = 0; i < 3; ++i) end = put_number(end, w[i], 15);
  }
  for (int c = 0; c < F3R_NCON; ++c) end = put_number(end, o->lambda[c], 10);
  end = put_number(end, o->kinetic_energy, 15);
  end = put_number(end, o->potential_energy, 15);
  end = put_number(end, o->external_work, 15);
  end = put_number(end, o->constraint_residual, 3);
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
#define MAX_OPTION_SETS 12
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
  st = f3r_accuracy_resolve(scene, 0, choice, &err);
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
  if (scene->accuracy > 0 && !choice->request_met)
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
 * NULL); returns 1 when the simulation failed (reported), 0 otherwise. */
static int run_outputs(const cli_options* o, const f3r_scene* scene, const f3r_model* model,
                       f3r_sim* sim, FILE* csv, run_stats* r) {
  static double shapes[3][101][F3R_MAX_MODES]; /* mode shapes at the stations */
  eval_mode_shapes(model, scene->beam_points, shapes);
  const long steps = (long)llround(scene->duration / scene->output_step);
  double held[F3R_MAX_Q] = {0};
  f3r_error err = {0};
  int rc = 0;
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
    if (csv) write_row(csv, model, out);
    if (st != F3R_OK) {
      cli_fail(f3r_status_name(st), "%s", err.message);
      rc = 1;
      break;
    }
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
  fprintf(human,
          "max deflection      %.6e m (largest |w| at %d stations a link; at the tips %.6e m)\n",
          r->max_deflection, scene->beam_points, r->max_tip);
  fprintf(human, "final pose          x_p %.9f y_p %.9f phi_p %.9f\n", out->q[F3R_Q_X],
          out->q[F3R_Q_Y], out->q[F3R_Q_PHI]);
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

/* The simulation with its CSV and summary (and what it leaves in *report); returns the exit
 * code. */
static int simulate(const cli_options* o, const f3r_scene* scene, const f3r_model* model,
                    run_report* report) {
  f3r_solver_settings settings = f3r_solver_settings_from_scene(scene);
  settings.analytic_jacobian = !o->fd_jacobian;
  settings.dense_linear_solver = o->dense_linear_solver;
  settings.stop_at_outputs = o->stop_at_outputs;
  for (int h = 0; h < o->n_holds; ++h)
    if (o->holds[h].index >= f3r_model_nq(model)) {
      cli_fail("usage", "--hold index %d is beyond nq = %d", o->holds[h].index,
               f3r_model_nq(model));
      return 2;
    }
  f3r_error err = {0};
  f3r_sim* sim = NULL;
  if (f3r_sim_create(model, &settings, &sim, &err) != F3R_OK) {
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
    write_header(csv, model);
    write_row(csv, model, f3r_sim_outputs(sim));
  }
  run_stats stats = {0};
  const int rc = run_outputs(o, scene, model, sim, csv, &stats);
  if (csv) fclose(csv);
  free(csv_buffer);
  print_summary(o, scene, model, f3r_sim_outputs(sim), &stats);
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
      if (rc < 0) rc = simulate(&o, &scene, model, &report);
    }
  }
  if (o.summary_json) rc = cli_write_summary(o.summary_json, &o, &parts, rc);
  f3r_model_destroy(model);
  f3r_scene_free(&scene);
  return rc;
}

/* The summaries' shared numbers and the JSON summary (run_report.h). */
#include "run_report.h"

#include <math.h>
#include <string.h>
#include <time.h>

#include <sundials/sundials_config.h>

#include "flex3rpr/kinds.h"
#include "flex3rpr/sim.h"
#include "summary_json.h"

const char* cli_integrator_text(const cli_options* o, const f3r_scene* scene) {
  const f3r_integrator_kind* kind = f3r_integrator_kind_at((int)scene->integrator);
  if (!kind) return "unknown";
  /* --fd-jacobian is IDA's choice of Newton Jacobian */
  if (scene->integrator != F3R_INTEGRATOR_IDA) return kind->description;
  return o->fd_jacobian ? "IDA, difference-quotient Jacobian" : "IDA, analytic Jacobian";
}

/* Simulated time over a measured time (inf when not measurable). */
static double per_second(double t, double time) { return time > 0 ? t / time : INFINITY; }

real_time_factors cli_real_time_factor(double t, const run_stats* r) {
  return (real_time_factors){per_second(t, r->cpu_total), per_second(t, r->wall_integrating),
                             per_second(t, r->wall_integrating + r->wall_outputs)};
}

double cli_energy_relative(const run_stats* r) {
  return r->max_energy > 0 ? r->max_energy_error / r->max_energy : 0.0;
}

int cli_energy_guard(const run_stats* r) {
  return f3r_energy_guard_tripped(r->max_energy_error, r->max_energy);
}

static void json_settings(f3r_json* j, const cli_options* o, const f3r_scene* scene,
                          const f3r_model* model) {
  const f3r_integrator_kind* kind = f3r_integrator_kind_at((int)scene->integrator);
  const int tables = kind && kind->tables, ida = scene->integrator == F3R_INTEGRATOR_IDA;
  f3r_json_object(j, "settings");
  f3r_json_string(j, "formulation", f3r_formulation_name(scene->formulation));
  f3r_json_string(j, "integrator", f3r_integrator_name(scene->integrator));
  f3r_json_string(j, "integrator_text", cli_integrator_text(o, scene));
  f3r_json_string(j, "jacobian", !ida ? NULL : o->fd_jacobian ? "difference_quotient" : "analytic");
  f3r_json_string(j, "table", !tables ? NULL : scene->table[0] ? scene->table : "default");
  f3r_json_number(j, "rtol", scene->rtol);
  f3r_json_number(j, "atol", scene->atol);
  if (ida)
    f3r_json_integer(j, "max_bdf_order", scene->max_order);
  else
    f3r_json_null(j, "max_bdf_order");
  f3r_json_bool(j, "exact_kinematics", scene->exact_kinematics);
  f3r_json_string(j, "sundials_version", SUNDIALS_VERSION);
  f3r_json_string(j, "sundials_build", F3R_SUNDIALS_BUILD);
  f3r_json_array(j, "link_basis");
  for (int i = 0; i < 3; ++i) {
    char basis[96];
    f3r_json_string(j, NULL, f3r_model_link_basis_name(model, i, basis, sizeof basis));
  }
  f3r_json_close(j);
  f3r_json_integer(j, "state_dimension", f3r_state_size(model, scene->formulation));
  f3r_json_integer(j, "nq", f3r_model_nq(model));
  f3r_json_number(j, "duration_s", scene->duration);
  f3r_json_number(j, "output_step_s", scene->output_step);
  f3r_json_integer(j, "beam_points", scene->beam_points);
  f3r_json_close(j);
}

static void json_run(f3r_json* j, const cli_options* o, const run_report* r) {
  const run_stats* s = &r->stats;
  f3r_json_object(j, "run");
  f3r_json_number(j, "simulated_time_s", r->t);
  f3r_json_integer(j, "steps", r->steps);
  f3r_json_integer(j, "residual_evals", r->residual_evals);
  f3r_json_integer(j, "jacobian_evals", r->jacobian_evals);
  f3r_json_number(j, "cpu_time_s", s->cpu_total);
  f3r_json_number(j, "wall_time_s", s->wall_total);
  f3r_json_number(j, "integration_wall_time_s", s->wall_integrating);
  f3r_json_number(j, "outputs_wall_time_s", s->wall_outputs);
  const real_time_factors rtf = cli_real_time_factor(r->t, s);
  f3r_json_number(j, "real_time_factor_cpu", rtf.cpu);
  f3r_json_number(j, "real_time_factor_wall_integration", rtf.wall_integration);
  f3r_json_number(j, "real_time_factor_wall", rtf.wall);
  f3r_json_number(j, "max_constraint_residual_m", s->max_constraint);
  f3r_json_number(j, "energy_balance_error_J", s->max_energy_error);
  f3r_json_number(j, "energy_balance_relative", cli_energy_relative(s));
  f3r_json_number(j, "max_deflection_m", s->max_deflection);
  f3r_json_number(j, "max_tip_deflection_m", s->max_tip);
  f3r_json_bool(j, "energy_guard", cli_energy_guard(s));
  if (s->end_stops) {
    f3r_json_integer(j, "impacts", s->impacts);
    f3r_json_array(j, "final_stop_force_N");
    for (int i = 0; i < 3; ++i) f3r_json_number(j, NULL, s->final_stop_force[i]);
    f3r_json_close(j);
    f3r_json_array(j, "max_stop_force_N");
    for (int i = 0; i < 3; ++i) f3r_json_number(j, NULL, s->max_stop_force[i]);
    f3r_json_close(j);
  }
  f3r_json_number(j, "check_cpu_time_s", r->configurations ? r->check_cpu : NAN);
  f3r_json_number(j, "final_x_p_m", r->x);
  f3r_json_number(j, "final_y_p_m", r->y);
  f3r_json_number(j, "final_phi_p_rad", r->phi);
  f3r_json_string(j, "csv", o->out_path);
  f3r_json_close(j);
}

/* The mode counts a link, and the static shapes the basis adds to them. */
static void json_links(f3r_json* j, const f3r_scene* scene, const f3r_accuracy_choice* c) {
  f3r_json_array(j, "rigid");
  for (int i = 0; i < 3; ++i) f3r_json_bool(j, NULL, scene->links[i].model == F3R_LINK_RIGID);
  f3r_json_close(j);
  f3r_json_array(j, "modes");
  for (int i = 0; i < 3; ++i) f3r_json_integer(j, NULL, c->modes[i]);
  f3r_json_close(j);
  f3r_json_array(j, "static_correction");
  for (int i = 0; i < 3; ++i) f3r_json_bool(j, NULL, c->static_correction[i]);
  f3r_json_close(j);
  f3r_json_array(j, "static_shapes");
  for (int i = 0; i < 3; ++i)
    f3r_json_integer(j, NULL,
                     c->static_correction[i] ? f3r_link_correction_functions(&scene->links[i]) : 0);
  f3r_json_close(j);
  f3r_json_array(j, "shape_mix"); /* the one mixed shape's load ratio, null for the pair */
  for (int i = 0; i < 3; ++i)
    if (c->static_correction[i] && isfinite(c->shape_mix[i]))
      f3r_json_number(j, NULL, c->shape_mix[i]);
    else
      f3r_json_null(j, NULL);
  f3r_json_close(j);
}

/* The accuracy knob's choice and estimates: with a request (--accuracy, scene accuracy), or the
 * mode counts of modes: auto alone (request_m null); null when it chose nothing. */
static void json_choice(f3r_json* j, const f3r_scene* scene, const f3r_accuracy_choice* c,
                        double choose_cpu) {
  const int request = scene->accuracy > 0;
  if (!request && !c->summary[0]) {
    f3r_json_null(j, "accuracy");
    return;
  }
  f3r_json_object(j, "accuracy");
  f3r_json_number(j, "request_m", request ? c->request : NAN);
  json_links(j, scene, c);
  f3r_json_number(j, "model_error_m", c->model_error);
  f3r_json_number(j, "extent_m", c->extent);
  f3r_json_integer(j, "linear_evaluations", c->linear_evaluations);
  f3r_json_number(j, "choice_cpu_time_s", choose_cpu);
  if (request) {
    f3r_json_bool(j, "exact_kinematics", c->exact_kinematics);
    f3r_json_string(j, "formulation", f3r_formulation_name(c->formulation));
    f3r_json_string(j, "integrator", f3r_integrator_name(c->integrator));
    f3r_json_string(j, "table", c->table[0] ? c->table : NULL);
    f3r_json_number(j, "rtol", c->rtol);
    f3r_json_number(j, "atol", c->atol);
    f3r_json_number(j, "kinematics_error_m", c->kinematics_error);
    f3r_json_number(j, "kinematics_effect_m", c->kinematics_effect);
    f3r_json_number(j, "kinematics_linear_m", c->kinematics_linear);
    f3r_json_number(j, "solver_error_m", c->solver_error);
    f3r_json_bool(j, "pilot", c->pilot);
    f3r_json_number(j, "pilot_ratio", c->pilot ? c->pilot_ratio : NAN);
  }
  f3r_json_number(j, "estimated_error_m", c->estimated_error);
  f3r_json_number(j, "measured_error_m", c->verified ? c->measured_error : NAN);
  f3r_json_string(j, "error_basis", !request ? NULL : c->verified ? "measured" : "estimated");
  f3r_json_integer(j, "configurations", c->configurations);
  f3r_json_bool(j, "request_met", c->request_met);
  f3r_json_string(j, "summary", c->summary);
  f3r_json_string(j, "brief", c->brief);
  f3r_json_close(j);
}

int cli_write_summary(const char* path, const cli_options* o, const summary_parts* p, int rc) {
  FILE* f = strcmp(path, "-") ? fopen(path, "w") : stdout;
  if (!f) {
    cli_fail("io", "cannot write %s", path);
    return rc ? rc : 1;
  }
  f3r_json j;
  f3r_json_begin(&j, f);
  f3r_json_string(&j, "format", "flex3rpr_sim summary 1");
  f3r_json_string(&j, "scene", o->scene_path);
  f3r_json_integer(&j, "exit_code", rc);
  if (rc) {
    f3r_json_object(&j, "error");
    f3r_json_string(&j, "status", cli_failure_status() ? cli_failure_status() : "failed");
    f3r_json_string(&j, "message", cli_failure_status() ? cli_failure_message() : "see stderr");
    f3r_json_close(&j);
  } else {
    f3r_json_null(&j, "error");
  }
  if (p->model)
    json_settings(&j, o, p->scene, p->model);
  else
    f3r_json_null(&j, "settings");
  if (p->choice)
    json_choice(&j, p->scene, p->choice, p->choose_cpu);
  else
    f3r_json_null(&j, "accuracy");
  if (p->run && p->run->ran)
    json_run(&j, o, p->run);
  else
    f3r_json_null(&j, "run");
  f3r_json_end(&j);
  if (f != stdout ? fclose(f) != 0 : fflush(f) != 0) {
    cli_fail("io", "cannot write %s", path);
    return rc ? rc : 1;
  }
  return rc;
}

/* Process CPU time in s, at nanosecond resolution (clock() has microsecond steps). A system
 * call of about 0.5 us: read twice per run only. */
double cli_cpu_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Monotonic time in s, read through the vDSO in about 20 ns: it splits the run into integration
 * and outputs at every output step. With the process CPU clock there, its two system calls per
 * output were half the "integration" time of a rigid run with 1 ms outputs. On an idle machine
 * the split adds up to the CPU time (the summary prints both). */
double cli_monotonic_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The basis functions of every link at its beam_points stations (beam_points <= 101). */
void cli_eval_mode_shapes(const f3r_model* model, int beam_points,
                          double shapes[3][101][F3R_MAX_MODES]) {
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = f3r_model_link(model, i);
    for (int k = 0; k < beam_points; ++k)
      for (int j = 0; j < lp->modes; ++j)
        f3r_model_link_shape(model, i, j, (double)k / (beam_points - 1), &shapes[i][k][j], NULL);
  }
}

void cli_track_maxima(run_stats* r, const f3r_model* model, int beam_points,
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

void cli_print_summary(FILE* human, const cli_options* o, const f3r_scene* scene,
                       const f3r_model* model, const f3r_outputs* out, const run_stats* r) {
  fprintf(human, "scene               %s\n", o->scene_path);
  fprintf(human, "formulation         %s, rtol %g, atol %g, %s\n",
          f3r_formulation_name(scene->formulation), scene->rtol, scene->atol,
          cli_integrator_text(o, scene));
  const f3r_integrator_kind* kind = f3r_integrator_kind_at((int)scene->integrator);
  if (kind && kind->tables)
    fprintf(human, "butcher table       %s\n", scene->table[0] ? scene->table : "default");
  if (kind && kind->has_order) fprintf(human, "max BDF order       %d\n", scene->max_order);
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
void cli_keep_report(const f3r_outputs* out, const run_stats* stats, run_report* report) {
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

void cli_report_choice(FILE* human, const cli_options* o, const f3r_scene* scene,
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

/* The summary's lines on the measurement, and the warnings of a request not met. */
void cli_report_measurement(FILE* human, const cli_options* o, const f3r_accuracy_choice* choice,
                            const f3r_measured_run* v, const run_stats* written) {
  const double request = v->scenes[0].accuracy;
  fprintf(human,
          "accuracy            measured %.3g m against a richer run (estimate %.3g m); "
          "request %g m %s (measured, within %g of it)\n",
          choice->measured_error, choice->estimated_error, request,
          choice->request_met ? "met" : "NOT met", F3R_CHECK_MARGIN);
  fprintf(human, "check cpu time      %.6f s (%.2f of the run's %.6f s; %d runs in all)\n",
          v->check_cpu, written->cpu_total > 0 ? v->check_cpu / written->cpu_total : 0,
          written->cpu_total, v->count);
  fprintf(human, "configurations      %s\n", v->attempts);
  if (v->stopped[0]) fprintf(human, "                    %s\n", v->stopped);
  if (!choice->request_met)
    fprintf(stderr,
            "flex3rpr_sim: %s: the accuracy request %g m is not met: measured %.3g m (it must be "
            "within %g of the request) after %d runs (%s); the path written is the one measured "
            "closest%s%s%s\n",
            o->scene_path, request, choice->measured_error, F3R_CHECK_MARGIN, v->count, v->attempts,
            v->scenes[v->accepted].accuracy_escalations ? "" : " (accuracy.escalations is 0)",
            v->stopped[0] ? "; " : "", v->stopped);
}

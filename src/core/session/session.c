/* The session (flex3rpr/session.h): open a scene, then step, set and reset it with every check in
 * one place. It only sequences the layers below; the physics is theirs. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "flex3rpr/closed_loop_check.h"
#include "flex3rpr/session.h"

struct f3r_session {
  f3r_scene scene; /* owns its input tables */
  f3r_model* model;
  f3r_sim* sim;
  f3r_accuracy_choice choice;
  f3r_sensors* sensors;         /* NULL when the scene enables none */
  f3r_sensors* sensors_saved;   /* their copy before a step, put back if it fails */
  f3r_sim_snapshot* saved;      /* the run before a step, put back if it fails */
  f3r_closed_loop_check* check; /* NULL without an accuracy request or with accuracy.verify
                                 * off */
  int measure_apart;            /* the shell drives the check (options.measure_apart) */
  double choose_cpu;            /* s: the knob's choice at open */
  long periods;
};

/* The simulation of a controller: commands take effect exactly at the periods' ends. */
static f3r_status create_sim(f3r_session* s, f3r_error* err) {
  f3r_solver_settings settings = f3r_solver_settings_from_scene(&s->scene);
  settings.stop_at_outputs = 1;
  f3r_status st = f3r_sim_create(s->model, &settings, &s->sim, err);
  if (st == F3R_OK) st = f3r_sim_snapshot_create(s->sim, &s->saved, err);
  return st;
}

/* The check of a scene with an accuracy request (and accuracy.verify on). */
static f3r_status create_check(f3r_session* s, f3r_error* err) {
  if (!(s->scene.accuracy > 0.0 && s->scene.accuracy_verify)) return F3R_OK;
  return f3r_closed_loop_check_create(&s->scene, s->model, &s->check, err);
}

static f3r_status create_sensors(f3r_session* s, f3r_error* err) {
  if (!f3r_sensors_any(&s->scene.sensors)) return F3R_OK;
  f3r_status st = f3r_sensors_create(s->model, &s->scene.sensors, &s->sensors, err);
  if (st == F3R_OK) st = f3r_sensors_create(s->model, &s->scene.sensors, &s->sensors_saved, err);
  if (st == F3R_OK) st = f3r_sensors_update(s->sensors, f3r_sim_outputs(s->sim), err);
  return st;
}

/* Process CPU time in s (the knob's cost, which a shell reports). */
static double cpu_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* What open does after the load: the knob's choice, the model, the simulation, the sensors and
 * the check, on s->scene. */
static f3r_status open_loaded(f3r_session* s, const f3r_session_options* options, f3r_error* err) {
  s->measure_apart = options->measure_apart;
  const double start = cpu_seconds();
  f3r_status st = f3r_accuracy_resolve(&s->scene, options->commanded, &s->choice, err);
  s->choose_cpu = cpu_seconds() - start;
  if (st == F3R_OK) st = f3r_model_create(&s->scene, &s->model, err);
  if (st != F3R_OK || options->model_only) return st;
  st = create_sim(s, err);
  if (st == F3R_OK) st = create_sensors(s, err);
  if (st == F3R_OK) st = create_check(s, err);
  return st;
}

/* Open from a scene file (scene NULL) or from a scene loaded already (copied). */
static f3r_status open_session(const char* scene_path, const f3r_scene* scene,
                               const f3r_session_options* options, f3r_session** out,
                               f3r_error* err) {
  *out = NULL;
  const f3r_session_options none = {0};
  if (!options) options = &none;
  f3r_session* s = calloc(1, sizeof *s);
  if (!s) return f3r_error_set(err, F3R_ERR_MEMORY, "no memory for a session");
  s->scene = f3r_default_scene();
  const f3r_scene_options source = {options->accuracy, options->overrides, options->override_count};
  f3r_status st = scene ? f3r_scene_copy(&s->scene, scene, err)
                        : f3r_scene_load_with(scene_path, &source, &s->scene, err);
  if (st == F3R_OK) st = open_loaded(s, options, err);
  if (st != F3R_OK) {
    f3r_session_close(s);
    return st;
  }
  *out = s;
  return F3R_OK;
}

f3r_status f3r_session_open(const char* scene_path, const f3r_session_options* options,
                            f3r_session** out, f3r_error* err) {
  return open_session(scene_path, NULL, options, out, err);
}

f3r_status f3r_session_open_scene(const f3r_scene* scene, const f3r_session_options* options,
                                  f3r_session** out, f3r_error* err) {
  return open_session(NULL, scene, options, out, err);
}

void f3r_session_close(f3r_session* s) {
  if (!s) return;
  f3r_closed_loop_check_destroy(s->check);
  f3r_sensors_destroy(s->sensors_saved);
  f3r_sensors_destroy(s->sensors);
  f3r_sim_snapshot_destroy(s->saved);
  f3r_sim_destroy(s->sim);
  f3r_model_destroy(s->model);
  f3r_scene_free(&s->scene);
  free(s);
}

const f3r_scene* f3r_session_scene(const f3r_session* s) { return &s->scene; }
const f3r_model* f3r_session_model(const f3r_session* s) { return s->model; }
const f3r_accuracy_choice* f3r_session_choice(const f3r_session* s) { return &s->choice; }
double f3r_session_choose_cpu(const f3r_session* s) { return s->choose_cpu; }
f3r_sim* f3r_session_sim(f3r_session* s) { return s->sim; }
const f3r_sensors* f3r_session_sensors(const f3r_session* s) { return s->sensors; }
long f3r_session_periods(const f3r_session* s) { return s->periods; }
f3r_closed_loop_check* f3r_session_closed_loop_check(f3r_session* s) {
  return s->measure_apart ? s->check : NULL;
}

int f3r_session_measurement(const f3r_session* s, double* measured, int* request_met,
                            const char** lost) {
  if (!s->check || s->measure_apart) return 0;
  *measured = f3r_closed_loop_check_measured(s->check, request_met, lost);
  return 1;
}

/* Generalized force n as a command names it, its limit and the scene field that sets it. */
typedef struct {
  char name[32];
  double limit;
  const char* field;
} force_limit;

static force_limit limit_of(const f3r_scene* scene, int n) {
  static const char* const kRigid[F3R_Q_MODAL] = {
      "leg_force_1",       "leg_force_2",       "leg_force_3",
      "cylinder_torque_1", "cylinder_torque_2", "cylinder_torque_3",
      "platform_force_x",  "platform_force_y",  "platform_torque"};
  force_limit f = {"", scene->limit_force, "limits.force"};
  if (n >= F3R_Q_MODAL) {
    snprintf(f.name, sizeof f.name, "modal_force[%d]", n - F3R_Q_MODAL);
    f.limit = scene->limit_modal_force, f.field = "limits.modal_force";
    return f;
  }
  snprintf(f.name, sizeof f.name, "%s", kRigid[n]);
  if ((n >= F3R_Q_THETA && n < F3R_Q_X) || n == F3R_Q_PHI)
    f.limit = scene->limit_torque, f.field = "limits.torque";
  return f;
}

f3r_status f3r_command_check(const f3r_scene* scene, const f3r_model* model, const double* forces,
                             int count, f3r_error* err) {
  const int nq = f3r_model_nq(model);
  if (!forces || count != nq)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "%d values, expected %d (every generalized force)",
                         forces ? count : 0, nq);
  for (int n = 0; n < nq; ++n) {
    const force_limit f = limit_of(scene, n);
    if (!isfinite(forces[n]))
      return f3r_error_set(err, F3R_ERR_ARGUMENT, "%s is %g, not finite", f.name, forces[n]);
    if (fabs(forces[n]) > f.limit)
      return f3r_error_set(err, F3R_ERR_ARGUMENT, "%s is %g, out of range %g..%g (the scene's %s)",
                           f.name, forces[n], -f.limit, f.limit, f.field);
  }
  return F3R_OK;
}

f3r_status f3r_session_check_forces(const f3r_session* s, const double* forces, int count,
                                    f3r_error* err) {
  const f3r_status st = f3r_command_check(&s->scene, s->model, forces, count, err);
  if (st != F3R_OK) {
    char why[sizeof err->message];
    snprintf(why, sizeof why, "%s", err->message);
    f3r_error_set(err, st, "command: %s; nothing changed", why);
  }
  return st;
}

f3r_status f3r_session_check_step(double periods, double period, f3r_error* err) {
  if (!(periods >= 1.0 && periods <= 1e9 && periods == floor(periods)))
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "periods is %g: a whole number in 1..1e9 expected; nothing changed",
                         periods);
  if (!(period >= 1e-9 && period <= 1e3))
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "period is %g s: out of range 1e-09..1000 s; nothing changed", period);
  return F3R_OK;
}

/* Keeps what a failed step must put back. */
static void save_step(f3r_session* s) {
  f3r_sim_save(s->sim, s->saved);
  if (s->sensors) f3r_sensors_copy(s->sensors_saved, s->sensors);
  if (s->check && !s->measure_apart) f3r_closed_loop_check_save(s->check);
}

/* Puts the run, its sensors and its check back as they were before a failed step. */
static void undo_step(f3r_session* s, long periods_before) {
  f3r_sim_restore(s->sim, s->saved, NULL); /* a restart at a state that ran before */
  if (s->sensors) f3r_sensors_copy(s->sensors, s->sensors_saved);
  if (s->check && !s->measure_apart) f3r_closed_loop_check_restore(s->check);
  s->periods = periods_before;
}

/* n periods of forces (checked), undone as a whole when one fails. */
static f3r_status step_periods(f3r_session* s, const double* forces, long n, double period,
                               f3r_error* err) {
  const long periods_before = s->periods;
  const int measure = s->check && !s->measure_apart;
  save_step(s);
  f3r_status st = F3R_OK;
  for (long k = 0; k < n && st == F3R_OK; ++k) {
    if ((st = f3r_sim_set_forces(s->sim, forces, err)) != F3R_OK) break;
    ++s->periods;
    const double t = (double)s->periods * period;
    st = f3r_sim_advance(s->sim, t, err);
    if (st == F3R_OK && measure)
      f3r_closed_loop_check_period(s->check, forces, t, f3r_sim_outputs(s->sim)->q + F3R_Q_X);
    if (st == F3R_OK && s->sensors)
      st = f3r_sensors_update(s->sensors, f3r_sim_outputs(s->sim), err);
  }
  if (st != F3R_OK) undo_step(s, periods_before);
  return st;
}

f3r_status f3r_session_step(f3r_session* s, const double* forces, int count, double periods,
                            double period, f3r_error* err) {
  f3r_status st = f3r_session_check_step(periods, period, err);
  if (st == F3R_OK) st = f3r_session_check_forces(s, forces, count, err);
  if (st != F3R_OK) return st;
  return step_periods(s, forces, (long)periods, period, err);
}

f3r_status f3r_session_advance(f3r_session* s, const double* forces, int count, double period,
                               f3r_error* err) {
  f3r_status st = f3r_session_check_step(1.0, period, err);
  const int nq = f3r_model_nq(s->model);
  if (st == F3R_OK && (!forces || count != nq))
    st = f3r_error_set(err, F3R_ERR_ARGUMENT, "forces: %d values, expected %d; nothing changed",
                       forces ? count : 0, nq);
  for (int n = 0; st == F3R_OK && n < nq; ++n)
    if (!isfinite(forces[n]))
      st = f3r_error_set(err, F3R_ERR_ARGUMENT, "forces[%d] is %g, not finite; nothing changed", n,
                         forces[n]);
  return st == F3R_OK ? step_periods(s, forces, 1, period, err) : st;
}

/* Each value within +-limit, else an error naming it. */
static f3r_status check_range(const double* values, int count, double limit, const char* what,
                              f3r_error* err) {
  for (int k = 0; values && k < count; ++k)
    if (!(fabs(values[k]) <= limit))
      return f3r_error_set(err, F3R_ERR_ARGUMENT,
                           "%s[%d] is %g: out of range %g..%g; nothing changed", what, k, values[k],
                           -limit, limit);
  return F3R_OK;
}

f3r_status f3r_session_check_state(const f3r_model* model, const double pose[3],
                                   const double twist[3], const double* modal,
                                   const double* modal_rate, int modal_count, f3r_error* err) {
  const int n_modal = f3r_model_nq(model) - F3R_Q_MODAL;
  if (!pose || !twist)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "set_state: the pose and the twist are needed");
  if (modal_count != 0 && modal_count != n_modal)
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "modal: %d values, the model has %d modal coordinates (or give none); "
                         "nothing changed",
                         modal_count, n_modal);
  f3r_status st = check_range(pose, 2, F3R_STATE_POSITION_LIMIT, "pose", err);
  if (st == F3R_OK && !(fabs(pose[2]) <= F3R_STATE_ANGLE_LIMIT))
    st = f3r_error_set(err, F3R_ERR_ARGUMENT,
                       "pose[2] is %g: out of range %g..%g rad; nothing "
                       "changed",
                       pose[2], -F3R_STATE_ANGLE_LIMIT, F3R_STATE_ANGLE_LIMIT);
  if (st == F3R_OK) st = check_range(twist, 3, F3R_STATE_RATE_LIMIT, "twist", err);
  if (st == F3R_OK) st = check_range(modal, modal_count, F3R_STATE_MODAL_LIMIT, "modal", err);
  if (st == F3R_OK)
    st = check_range(modal_rate, modal_count, F3R_STATE_MODAL_RATE_LIMIT, "modal_rate", err);
  return st;
}

f3r_status f3r_session_set_state(f3r_session* s, const double pose[3], const double twist[3],
                                 const double* modal, const double* modal_rate, int modal_count,
                                 f3r_error* err) {
  f3r_status st =
      f3r_session_check_state(s->model, pose, twist, modal, modal_rate, modal_count, err);
  if (!modal_count) modal = modal_rate = NULL;
  if (st == F3R_OK &&
      (st = f3r_sim_set_state(s->sim, pose, twist, modal, modal_rate, err)) != F3R_OK) {
    char why[sizeof err->message];
    snprintf(why, sizeof why, "%s", err->message);
    f3r_error_set(err, st, "%s; nothing changed", why);
  }
  if (st == F3R_OK && s->check && !s->measure_apart)
    f3r_closed_loop_check_set_state(s->check, pose, twist, modal || modal_rate);
  return st;
}

f3r_status f3r_session_reset(f3r_session* s, f3r_error* err) {
  f3r_status st = f3r_sim_reset(s->sim, err);
  s->periods = 0;
  if (st == F3R_OK && s->check && !s->measure_apart)
    st = f3r_closed_loop_check_reset(s->check, err);
  if (st == F3R_OK && s->sensors) {
    f3r_sensors_reset(s->sensors);
    st = f3r_sensors_update(s->sensors, f3r_sim_outputs(s->sim), err);
  }
  return st;
}

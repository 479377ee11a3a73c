/* The closed-loop measurement (flex3rpr/closed_loop_check.h): the check configuration stepped
 * on the run's commands, and the end-effector distance at the periods' ends. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/accuracy.h"
#include "flex3rpr/closed_loop_check.h"
#include "flex3rpr/sim.h"

struct f3r_closed_loop_check {
  f3r_scene scene; /* a view sharing the run scene's tables */
  const f3r_model* run_model;
  double request; /* m */
  f3r_model* model;
  f3r_sim* sim;
  f3r_sim_snapshot* saved;
  double held[F3R_MAX_Q];          /* the command in the check's layout */
  double measured, measured_saved; /* m; NaN once the check could not follow */
  char lost[256], lost_saved[256]; /* why it could not, or empty */
};

f3r_status f3r_closed_loop_check_create(const f3r_scene* scene, const f3r_model* run_model,
                                        f3r_closed_loop_check** out, f3r_error* err) {
  *out = NULL;
  f3r_closed_loop_check* c = calloc(1, sizeof *c);
  if (!c) return f3r_error_set(err, F3R_ERR_MEMORY, "no memory for the accuracy check");
  c->run_model = run_model;
  c->request = scene->accuracy;
  f3r_accuracy_check_scene(scene, 0, &c->scene);
  f3r_solver_settings settings = f3r_solver_settings_from_scene(&c->scene);
  settings.stop_at_outputs = 1; /* commands take effect exactly at the periods' ends */
  f3r_status st = f3r_model_create(&c->scene, &c->model, err);
  if (st == F3R_OK) st = f3r_sim_create(c->model, &settings, &c->sim, err);
  if (st == F3R_OK) st = f3r_sim_snapshot_create(c->sim, &c->saved, err);
  if (st != F3R_OK) {
    f3r_closed_loop_check_destroy(c);
    return f3r_error_set(err, st, "the accuracy check: %s", err->message);
  }
  *out = c;
  return F3R_OK;
}

void f3r_closed_loop_check_destroy(f3r_closed_loop_check* c) {
  if (!c) return;
  f3r_sim_snapshot_destroy(c->saved);
  f3r_sim_destroy(c->sim);
  f3r_model_destroy(c->model);
  free(c);
}

/* The command in the check's layout: the rigid forces as they are, each link's modal forces on
 * its first functions (the check's basis begins with the run's modes), zero beyond. */
static void check_layout(f3r_closed_loop_check* c, const double* forces) {
  double* held = c->held;
  memset(held, 0, F3R_MAX_Q * sizeof(double));
  memcpy(held, forces, F3R_Q_MODAL * sizeof(double));
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* run = f3r_model_link(c->run_model, i);
    const f3r_link_params* check = f3r_model_link(c->model, i);
    const int n = run->modes < check->modes ? run->modes : check->modes;
    for (int j = 0; j < n; ++j) held[check->eta_index + j] = forces[run->eta_index + j];
  }
}

void f3r_closed_loop_check_period(f3r_closed_loop_check* c, const double* forces, double t,
                                  const double run_xy[2]) {
  if (isnan(c->measured)) return;
  f3r_error err = {0};
  check_layout(c, forces);
  f3r_status st = f3r_sim_set_forces(c->sim, c->held, &err);
  if (st == F3R_OK) st = f3r_sim_advance(c->sim, t, &err);
  if (st != F3R_OK) {
    c->measured = NAN;
    snprintf(c->lost, sizeof c->lost, "the check stopped at t = %.9g s: %s", t, err.message);
    return;
  }
  const double* q = f3r_sim_outputs(c->sim)->q;
  c->measured = fmax(c->measured, hypot(run_xy[0] - q[F3R_Q_X], run_xy[1] - q[F3R_Q_Y]));
}

void f3r_closed_loop_check_lose(f3r_closed_loop_check* c, const char* why) {
  if (isnan(c->measured)) return; /* the first reason stays */
  c->measured = NAN;
  snprintf(c->lost, sizeof c->lost, "%s", why);
}

void f3r_closed_loop_check_set_state(f3r_closed_loop_check* c, const double pose[3],
                                     const double twist[3], int has_modal) {
  if (isnan(c->measured)) return;
  f3r_error err = {0};
  if (has_modal) {
    f3r_closed_loop_check_lose(c,
                               "a modal state was set, which the check's richer basis cannot "
                               "take (~reset starts a new measurement)");
  } else if (f3r_sim_set_state(c->sim, pose, twist, NULL, NULL, &err) != F3R_OK) {
    char why[256];
    snprintf(why, sizeof why, "the check could not take the state set: %s", err.message);
    f3r_closed_loop_check_lose(c, why);
  }
}

f3r_status f3r_closed_loop_check_reset(f3r_closed_loop_check* c, f3r_error* err) {
  c->measured = 0.0;
  c->lost[0] = '\0';
  return f3r_sim_reset(c->sim, err);
}

void f3r_closed_loop_check_save(f3r_closed_loop_check* c) {
  f3r_sim_save(c->sim, c->saved);
  c->measured_saved = c->measured;
  memcpy(c->lost_saved, c->lost, sizeof c->lost);
}

void f3r_closed_loop_check_restore(f3r_closed_loop_check* c) {
  f3r_sim_restore(c->sim, c->saved, NULL); /* a restart at a state that ran before */
  c->measured = c->measured_saved;
  memcpy(c->lost, c->lost_saved, sizeof c->lost);
}

double f3r_closed_loop_check_measured(const f3r_closed_loop_check* c, int* request_met,
                                      const char** lost) {
  if (request_met) *request_met = c->measured <= F3R_CHECK_MARGIN * c->request;
  if (lost) *lost = c->lost;
  return c->measured;
}

double f3r_closed_loop_check_request(const f3r_closed_loop_check* c) { return c->request; }

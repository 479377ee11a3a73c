/* The Python module's C side (src/flex3rpr/_core.py loads it with ctypes): one scene, its model
 * and one simulation behind a handle, and the loops that would cost a Python call a period. It
 * only sequences the core's public calls, as the CLI and the node do: no physics here.
 *
 * Every function that can fail returns an f3r_status and leaves the message in the handle
 * (f3r_py_message); on failure the simulation keeps its state, as the core's calls guarantee. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/accuracy.h"
#include "flex3rpr/linear.h"
#include "flex3rpr/modal.h"
#include "flex3rpr/output_columns.h"
#include "flex3rpr/sensors.h"
#include "flex3rpr/sim.h"

#define F3R_PY_EXPORT __attribute__((visibility("default")))

typedef struct {
  f3r_scene scene;
  f3r_model* model;
  f3r_sim* sim;
  f3r_accuracy_choice choice;
  f3r_sensors* sensors; /* the scene's sensors, sampled at every period's end; NULL: none */
  long periods; /* periods stepped since the start or the last reset, as the node counts them:
                 * period k ends at exactly k * period */
  char message[2048];
} f3r_py;

static f3r_status fail(f3r_py* p, const f3r_error* err, f3r_status status) {
  snprintf(p->message, sizeof p->message, "%s", err->message);
  return status;
}

/* The simulation of the scene's settings; controller: commands take effect exactly at the
 * periods' ends, as in the node (stop_at_outputs); else the CLI's default. */
static f3r_status make_sim(f3r_py* p, int controller, f3r_sim** sim) {
  f3r_error err = {0};
  f3r_solver_settings settings = f3r_solver_settings_from_scene(&p->scene);
  settings.stop_at_outputs = controller;
  const f3r_status st = f3r_sim_create(p->model, &settings, sim, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}

F3R_PY_EXPORT const char* f3r_py_message(const f3r_py* p) { return p->message; }

F3R_PY_EXPORT void f3r_py_destroy(f3r_py* p) {
  if (!p) return;
  f3r_sensors_destroy(p->sensors);
  f3r_sim_destroy(p->sim);
  f3r_model_destroy(p->model);
  f3r_scene_free(&p->scene);
  free(p);
}

/* Loads path with the overrides ("FIELD=VALUE", as --set) and an accuracy request (> 0), lets the
 * knob fix what the scene leaves open (commanded: held commands, as the node's), and builds the
 * model and a simulation at t = 0. On failure *out is a handle holding only the message. */
F3R_PY_EXPORT f3r_status f3r_py_create(const char* path, double accuracy, const char* const* sets,
                                       int n_sets, int commanded, f3r_py** out) {
  f3r_py* p = calloc(1, sizeof *p);
  *out = p;
  if (!p) return F3R_ERR_MEMORY;
  f3r_error err = {0};
  const f3r_scene_options options = {accuracy, sets, n_sets};
  f3r_status st = f3r_scene_load_with(path, &options, &p->scene, &err);
  if (st != F3R_OK) return fail(p, &err, st);
  if ((st = f3r_accuracy_resolve(&p->scene, commanded, &p->choice, &err)) != F3R_OK ||
      (st = f3r_model_create(&p->scene, &p->model, &err)) != F3R_OK)
    return fail(p, &err, st);
  if ((st = make_sim(p, 1, &p->sim)) != F3R_OK) return st;
  if (!f3r_sensors_any(&p->scene.sensors)) return F3R_OK;
  if ((st = f3r_sensors_create(p->model, &p->scene.sensors, &p->sensors, &err)) != F3R_OK ||
      (st = f3r_sensors_update(p->sensors, f3r_sim_outputs(p->sim), &err)) != F3R_OK)
    return fail(p, &err, st);
  return F3R_OK;
}

/* The enabled sensors' readings (encoders, gauges, accelerometer, as the CLI's columns) into
 * values; returns their count (0 without sensors). */
F3R_PY_EXPORT int f3r_py_sensors(const f3r_py* p, double* values) {
  int n = 0;
  for (int k = 0; p->sensors && k < F3R_SENSOR_KINDS; ++k) {
    const f3r_sensor_reading* r = f3r_sensors_reading(p->sensors, k);
    for (int c = 0; r->enabled && c < r->channels; ++c) values[n++] = r->value[c];
  }
  return n;
}

/* 1 when sensor kind (F3R_SENSOR_*) is enabled. */
F3R_PY_EXPORT int f3r_py_sensor_enabled(const f3r_py* p, int kind) {
  return p->sensors && f3r_sensors_reading(p->sensors, kind)->enabled;
}

F3R_PY_EXPORT int f3r_py_nq(const f3r_py* p) { return f3r_model_nq(p->model); }
F3R_PY_EXPORT int f3r_py_modes(const f3r_py* p, int link) {
  return f3r_model_link(p->model, link)->modes;
}
F3R_PY_EXPORT double f3r_py_time(const f3r_py* p) { return f3r_sim_time(p->sim); }
F3R_PY_EXPORT double f3r_py_duration(const f3r_py* p) { return p->scene.duration; }
F3R_PY_EXPORT double f3r_py_output_step(const f3r_py* p) { return p->scene.output_step; }
F3R_PY_EXPORT const f3r_geometry* f3r_py_geometry(const f3r_py* p) {
  static _Thread_local f3r_geometry g;
  g = f3r_model_geometry(p->model);
  return &g;
}
F3R_PY_EXPORT int f3r_py_columns(const f3r_py* p) { return f3r_output_columns(p->model); }
F3R_PY_EXPORT int f3r_py_column_name(const f3r_py* p, int k, char* name) {
  return f3r_output_column_name(p->model, k, name);
}

/* The present outputs, in the columns of output_columns.h. */
F3R_PY_EXPORT void f3r_py_row(f3r_py* p, double* row) {
  f3r_output_row(p->model, f3r_sim_outputs(p->sim), row);
}

/* The present outputs' fields the columns leave out: the actuators' and passive efforts (6 each),
 * the stops' state (3) and forces (3), the energy balance error, the actuation condition and the
 * impacts, in that order (21 values). */
F3R_PY_EXPORT void f3r_py_extras(f3r_py* p, double* extras) {
  const f3r_outputs* o = f3r_sim_outputs(p->sim);
  for (int j = 0; j < 6; ++j) extras[j] = o->actuator[j], extras[6 + j] = o->passive[j];
  for (int i = 0; i < 3; ++i) extras[12 + i] = o->stop_locked[i], extras[15 + i] = o->stop_force[i];
  extras[18] = o->energy_balance_error;
  extras[19] = o->actuation_condition;
  extras[20] = (double)o->impacts;
}

/* Holds the generalized forces held (nq) for `periods` periods of `period` s each, as the node's
 * ~step_with_command does (the forces set, then the integration to the period's end, k * period
 * since the start), and writes the outputs at the end into row. A failure stops at the last good
 * state, on the period grid. */
F3R_PY_EXPORT f3r_status f3r_py_step(f3r_py* p, const double* held, long periods, double period,
                                     double* row) {
  f3r_error err = {0};
  f3r_status st = F3R_OK;
  for (long k = 0; k < periods && st == F3R_OK; ++k) {
    if ((st = f3r_sim_set_forces(p->sim, held, &err)) != F3R_OK) break;
    ++p->periods;
    if ((st = f3r_sim_advance(p->sim, (double)p->periods * period, &err)) != F3R_OK)
      p->periods = (long)floor(f3r_sim_time(p->sim) / period + 1e-9);
    else if (p->sensors)
      st = f3r_sensors_update(p->sensors, f3r_sim_outputs(p->sim), &err);
  }
  if (row) f3r_py_row(p, row);
  return st == F3R_OK ? st : fail(p, &err, st);
}

F3R_PY_EXPORT f3r_status f3r_py_reset(f3r_py* p) {
  f3r_error err = {0};
  f3r_status st = f3r_sim_reset(p->sim, &err);
  p->periods = 0;
  if (st == F3R_OK && p->sensors) {
    f3r_sensors_reset(p->sensors);
    st = f3r_sensors_update(p->sensors, f3r_sim_outputs(p->sim), &err);
  }
  return st == F3R_OK ? st : fail(p, &err, st);
}

F3R_PY_EXPORT f3r_status f3r_py_set_state(f3r_py* p, const double* pose, const double* twist,
                                          const double* modal, const double* modal_rate) {
  f3r_error err = {0};
  const f3r_status st = f3r_sim_set_state(p->sim, pose, twist, modal, modal_rate, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* The scene from t = 0 as the CLI runs it (its own simulation, the CLI's solver settings, the
 * scripted inputs, outputs at k * output_step and the last at the duration): rows (count + 1 of
 * them, count = round(duration / output_step)) in the columns of output_columns.h. The handle's
 * simulation is untouched. Returns the rows written through *written. */
F3R_PY_EXPORT f3r_status f3r_py_run(f3r_py* p, double duration, double* rows, long* written) {
  f3r_sim* sim = NULL;
  f3r_status st = make_sim(p, 0, &sim);
  if (st != F3R_OK) return st;
  const int width = f3r_output_columns(p->model);
  const long count = (long)llround(duration / p->scene.output_step);
  f3r_error err = {0};
  f3r_output_row(p->model, f3r_sim_outputs(sim), rows);
  *written = 1;
  for (long k = 1; k <= count && st == F3R_OK; ++k) {
    const double t = k == count ? duration : (double)k * p->scene.output_step;
    st = f3r_sim_advance(sim, t, &err);
    f3r_output_row(p->model, f3r_sim_outputs(sim), rows + (size_t)k * (size_t)width);
    *written = k + 1;
  }
  f3r_sim_destroy(sim);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* The linearisation's state space (flex3rpr/linear.h); free it with f3r_py_linear_destroy. */
F3R_PY_EXPORT f3r_status f3r_py_linearise(f3r_py* p, f3r_state_space** ss) {
  f3r_error err = {0};
  const f3r_status st = f3r_state_space_create(p->model, ss, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}
F3R_PY_EXPORT void f3r_py_linear_destroy(f3r_state_space* ss) { f3r_state_space_destroy(ss); }

F3R_PY_EXPORT f3r_status f3r_py_modal(f3r_py* p, double* hz, int* count) {
  f3r_error err = {0};
  const f3r_status st = f3r_modal_frequencies(p->model, hz, count, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* The accuracy knob's choice as JSON (an object; "request": 0 when nothing was asked). */
F3R_PY_EXPORT const char* f3r_py_choice(f3r_py* p) {
  const f3r_accuracy_choice* c = &p->choice;
  char text[sizeof c->summary * 2];
  size_t n = 0; /* the summary's quotes, backslashes and line ends escaped */
  for (const char* s = c->summary; *s && n + 2 < sizeof text; ++s) {
    if (*s == '"' || *s == '\\') text[n++] = '\\';
    if (*s == '\n') {
      text[n++] = '\\', text[n++] = 'n';
      continue;
    }
    text[n++] = *s;
  }
  text[n] = '\0';
  snprintf(p->message, sizeof p->message,
           "{\"request\": %.17g, \"modes\": [%d, %d, %d], \"static_correction\": [%d, %d, %d], "
           "\"exact_kinematics\": %s, \"formulation\": \"%s\", \"integrator\": \"%s\", "
           "\"table\": \"%s\", \"rtol\": %.17g, \"atol\": %.17g, \"model_error\": %.17g, "
           "\"kinematics_error\": %.17g, \"solver_error\": %.17g, \"estimated_error\": %.17g, "
           "\"request_met\": %s, \"error_basis\": \"estimated\", \"summary\": \"%s\"}",
           c->request, c->modes[0], c->modes[1], c->modes[2], c->static_correction[0],
           c->static_correction[1], c->static_correction[2], c->exact_kinematics ? "true" : "false",
           f3r_formulation_name(p->scene.formulation), f3r_integrator_name(p->scene.integrator),
           p->scene.table, p->scene.rtol, p->scene.atol, c->model_error, c->kinematics_error,
           c->solver_error, c->estimated_error, c->request_met ? "true" : "false", text);
  return p->message;
}

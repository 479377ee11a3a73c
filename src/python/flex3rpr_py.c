/* The Python module's C side (src/flex3rpr/_core.py loads it with ctypes): a session
 * (flex3rpr/session.h) behind a handle, and the loops that would cost a Python call a period. It
 * only sequences the core's public calls: the checks of commands and states are the session's,
 * as for the node and the CLI.
 *
 * Every function that can fail returns an f3r_status and leaves the message in the handle
 * (f3r_py_message); on failure the session keeps its state. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/accuracy.h"
#include "flex3rpr/linear.h"
#include "flex3rpr/modal.h"
#include "flex3rpr/output_columns.h"
#include "flex3rpr/sensors.h"
#include "flex3rpr/session.h"
#include "flex3rpr/sim.h"

#define F3R_PY_EXPORT __attribute__((visibility("default")))

typedef struct {
  f3r_session* session;
  char message[2048];
  char choice_json[sizeof(((f3r_accuracy_choice*)0)->summary) * 2 + 1024]; /* f3r_py_choice */
} f3r_py;

static f3r_status fail(f3r_py* p, const f3r_error* err, f3r_status status) {
  snprintf(p->message, sizeof p->message, "%s", err->message);
  return status;
}

static const f3r_model* model_of(const f3r_py* p) { return f3r_session_model(p->session); }
static const f3r_scene* scene_of(const f3r_py* p) { return f3r_session_scene(p->session); }
static f3r_sim* sim_of(f3r_py* p) { return f3r_session_sim(p->session); }

F3R_PY_EXPORT const char* f3r_py_message(const f3r_py* p) { return p->message; }

F3R_PY_EXPORT void f3r_py_destroy(f3r_py* p) {
  if (!p) return;
  f3r_session_close(p->session);
  free(p);
}

/* Opens path with the overrides ("FIELD=VALUE", as --set) and an accuracy request (> 0) as a
 * session (commanded: commands held over periods, as the node's). On failure *out is a handle
 * holding only the message. */
F3R_PY_EXPORT f3r_status f3r_py_create(const char* path, double accuracy, const char* const* sets,
                                       int n_sets, int commanded, f3r_py** out) {
  f3r_py* p = calloc(1, sizeof *p);
  *out = p;
  if (!p) return F3R_ERR_MEMORY;
  f3r_error err = {0};
  const f3r_session_options options = {accuracy, sets, n_sets, commanded, 0, 0};
  const f3r_status st = f3r_session_open(path, &options, &p->session, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* The enabled sensors' readings (the CLI's columns, f3r_sensors_row) into values; returns their
 * count (0 without sensors). */
F3R_PY_EXPORT int f3r_py_sensors(const f3r_py* p, double* values) {
  const f3r_sensors* sensors = f3r_session_sensors(p->session);
  return sensors ? f3r_sensors_row(sensors, values) : 0;
}

/* The sensor kinds' table (kinds.h): the count; kind k's name (key -1) or the scene key of its
 * noise[0], noise[1], resolution[0], resolution[1] (key 0..3; NULL where it has none). */
F3R_PY_EXPORT int f3r_py_sensor_kinds(void) { return f3r_sensor_kind_count(); }
F3R_PY_EXPORT const char* f3r_py_sensor_kind_key(int kind, int key) {
  const f3r_sensor_kind* k = f3r_sensor_kind_at(kind);
  if (!k || key < -1 || key > 3) return NULL;
  return key < 0 ? k->name : key < 2 ? k->noise_key[key] : k->resolution_key[key - 2];
}

/* The enabled sensors' column count, and column i's name (kinds.h's table). */
F3R_PY_EXPORT int f3r_py_sensor_columns(const f3r_py* p) {
  const f3r_sensors* sensors = f3r_session_sensors(p->session);
  return sensors ? f3r_sensors_columns(sensors) : 0;
}
F3R_PY_EXPORT const char* f3r_py_sensor_column_name(const f3r_py* p, int column) {
  return f3r_sensors_column_name(f3r_session_sensors(p->session), column);
}

/* The scene's settings of sensor kind (F3R_SENSOR_*) as the session has them (overrides
 * applied): enabled, rate, delay, seed, noise[0], noise[1], resolution[0], resolution[1]. */
F3R_PY_EXPORT void f3r_py_sensor_settings(const f3r_py* p, int kind, double* values) {
  const f3r_sensor_scene* s = &scene_of(p)->sensors.kind[kind];
  const double v[8] = {s->enabled,  s->rate,     s->delay,         s->seed,
                       s->noise[0], s->noise[1], s->resolution[0], s->resolution[1]};
  memcpy(values, v, sizeof v);
}

/* Link's root strain gauge as a row over its modal coordinates (f3r_sensors_strain_row):
 * returns the count written to c (0 for a rigid link). */
F3R_PY_EXPORT int f3r_py_strain_row(const f3r_py* p, int link, double* c) {
  return f3r_sensors_strain_row(model_of(p), link, c);
}

F3R_PY_EXPORT int f3r_py_nq(const f3r_py* p) { return f3r_model_nq(model_of(p)); }
F3R_PY_EXPORT int f3r_py_modes(const f3r_py* p, int link) {
  return f3r_model_link(model_of(p), link)->modes;
}
F3R_PY_EXPORT double f3r_py_time(f3r_py* p) { return f3r_sim_time(sim_of(p)); }
F3R_PY_EXPORT double f3r_py_duration(const f3r_py* p) { return scene_of(p)->duration; }
F3R_PY_EXPORT double f3r_py_output_step(const f3r_py* p) { return scene_of(p)->output_step; }
F3R_PY_EXPORT const f3r_geometry* f3r_py_geometry(const f3r_py* p) {
  static _Thread_local f3r_geometry g;
  g = f3r_model_geometry(model_of(p));
  return &g;
}
/* The loop closure (f3r_model_close_loops): q (nq values) with the platform pose and modal
 * coordinates set gets the legs' rho and theta. A pose the legs cannot reach fails, q as it was. */
F3R_PY_EXPORT f3r_status f3r_py_close_loops(f3r_py* p, double* q) {
  const f3r_model* model = model_of(p);
  double full[F3R_MAX_Q] = {0};
  const size_t size = (size_t)f3r_model_nq(model) * sizeof *q;
  memcpy(full, q, size);
  const f3r_status st = f3r_model_close_loops(model, full);
  if (st != F3R_OK) {
    snprintf(p->message, sizeof p->message,
             "close_loops: the legs cannot reach the pose (%g, %g, %g) with these deflections",
             q[6], q[7], q[8]);
    return st;
  }
  memcpy(q, full, size);
  return F3R_OK;
}
F3R_PY_EXPORT int f3r_py_columns(const f3r_py* p) { return f3r_output_columns(model_of(p)); }
F3R_PY_EXPORT int f3r_py_column_name(const f3r_py* p, int k, char* name) {
  return f3r_output_column_name(model_of(p), k, name);
}

/* The present outputs, in the columns of output_columns.h. */
F3R_PY_EXPORT void f3r_py_row(f3r_py* p, double* row) {
  f3r_output_row(model_of(p), f3r_sim_outputs(sim_of(p)), row);
}

/* The outputs' fields the columns leave out, by name: f3r_py_extras writes them in this table's
 * order, each its count of values; Python slices them by these names. */
static const struct {
  const char* name;
  int count;
} kExtras[] = {{"actuator", 6},
               {"passive", 6},
               {"stop_locked", 3},
               {"stop_force", 3},
               {"energy_balance_error", 1},
               {"actuation_condition", 1},
               {"impacts", 1}};
#define EXTRA_GROUPS ((int)(sizeof kExtras / sizeof kExtras[0]))

/* Group k's name and value count (0 and NULL past the last group). */
F3R_PY_EXPORT const char* f3r_py_extra_group(int k, int* count) {
  *count = k >= 0 && k < EXTRA_GROUPS ? kExtras[k].count : 0;
  return k >= 0 && k < EXTRA_GROUPS ? kExtras[k].name : NULL;
}

/* The present outputs' extras in kExtras' order; returns how many values. */
F3R_PY_EXPORT int f3r_py_extras(f3r_py* p, double* extras) {
  const f3r_outputs* o = f3r_sim_outputs(sim_of(p));
  for (int j = 0; j < 6; ++j) extras[j] = o->actuator[j], extras[6 + j] = o->passive[j];
  for (int i = 0; i < 3; ++i) extras[12 + i] = o->stop_locked[i], extras[15 + i] = o->stop_force[i];
  extras[18] = o->energy_balance_error;
  extras[19] = o->actuation_condition;
  extras[20] = (double)o->impacts;
  return 21;
}

/* Holds the generalized forces held (count values, checked by the session) for `periods` whole
 * periods of `period` s, as the node's ~step_with_command, and writes the outputs at the end into
 * row (when not NULL). A refused command or a failed step changes nothing. */
F3R_PY_EXPORT f3r_status f3r_py_step(f3r_py* p, const double* held, int count, double periods,
                                     double period, double* row) {
  f3r_error err = {0};
  const f3r_status st = f3r_session_step(p->session, held, count, periods, period, &err);
  if (row) f3r_py_row(p, row);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* The closed-loop measurement (f3r_session_measurement): 1 when measuring, with the error (m),
 * whether the request is met and, in the message, why the check stopped (or ""). */
F3R_PY_EXPORT int f3r_py_measurement(f3r_py* p, double* measured, int* request_met) {
  const char* lost = "";
  const int measuring = f3r_session_measurement(p->session, measured, request_met, &lost);
  snprintf(p->message, sizeof p->message, "%s", measuring ? lost : "");
  return measuring;
}

/* Whether the session would step `periods` periods of `period` s (the message says why not). */
F3R_PY_EXPORT f3r_status f3r_py_check_step(f3r_py* p, double periods, double period) {
  f3r_error err = {0};
  const f3r_status st = f3r_session_check_step(periods, period, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}

F3R_PY_EXPORT f3r_status f3r_py_reset(f3r_py* p) {
  f3r_error err = {0};
  const f3r_status st = f3r_session_reset(p->session, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* pose and twist (3 values each), modal and modal_rate (modal_count values each, or NULL for
 * zeros), checked by the session. */
F3R_PY_EXPORT f3r_status f3r_py_set_state(f3r_py* p, const double* pose, const double* twist,
                                          const double* modal, const double* modal_rate,
                                          int modal_count) {
  f3r_error err = {0};
  const f3r_status st =
      f3r_session_set_state(p->session, pose, twist, modal, modal_rate, modal_count, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* The scene from t = 0 as the CLI runs it (its own simulation, the CLI's solver settings, the
 * scripted inputs, outputs at k * output_step and the last at the duration): rows (count + 1 of
 * them, count = round(duration / output_step)) in the columns of output_columns.h. The handle's
 * simulation is untouched. Returns the rows written through *written. */
F3R_PY_EXPORT f3r_status f3r_py_run(f3r_py* p, double duration, double* rows, long* written) {
  const f3r_model* model = model_of(p);
  const f3r_solver_settings settings = f3r_solver_settings_from_scene(scene_of(p));
  f3r_error err = {0};
  f3r_sim* sim = NULL;
  f3r_status st = f3r_sim_create(model, &settings, &sim, &err);
  if (st != F3R_OK) return fail(p, &err, st);
  const int width = f3r_output_columns(model);
  const double output_step = scene_of(p)->output_step;
  const long count = (long)llround(duration / output_step);
  f3r_output_row(model, f3r_sim_outputs(sim), rows);
  *written = 1;
  for (long k = 1; k <= count && st == F3R_OK; ++k) {
    const double t = k == count ? duration : (double)k * output_step;
    st = f3r_sim_advance(sim, t, &err);
    f3r_output_row(model, f3r_sim_outputs(sim), rows + (size_t)k * (size_t)width);
    *written = k + 1;
  }
  f3r_sim_destroy(sim);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* The linearisation's state space (flex3rpr/linear.h); free it with f3r_py_linear_destroy. */
F3R_PY_EXPORT f3r_status f3r_py_linearise(f3r_py* p, f3r_state_space** ss) {
  f3r_error err = {0};
  const f3r_status st = f3r_state_space_create(model_of(p), ss, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}
F3R_PY_EXPORT void f3r_py_linear_destroy(f3r_state_space* ss) { f3r_state_space_destroy(ss); }

F3R_PY_EXPORT f3r_status f3r_py_modal(f3r_py* p, double* hz, int* count) {
  f3r_error err = {0};
  const f3r_status st = f3r_modal_frequencies(model_of(p), hz, count, &err);
  return st == F3R_OK ? st : fail(p, &err, st);
}

/* The accuracy knob's choice as JSON (an object; "request": 0 when nothing was asked). */
F3R_PY_EXPORT const char* f3r_py_choice(f3r_py* p) {
  const f3r_accuracy_choice* c = f3r_session_choice(p->session);
  const f3r_scene* scene = scene_of(p);
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
  snprintf(p->choice_json, sizeof p->choice_json,
           "{\"request\": %.17g, \"excitation_N\": %.17g, \"modes\": [%d, %d, %d], "
           "\"static_correction\": [%d, %d, %d], "
           "\"exact_kinematics\": %s, \"formulation\": \"%s\", \"integrator\": \"%s\", "
           "\"table\": \"%s\", \"rtol\": %.17g, \"atol\": %.17g, \"model_error\": %.17g, "
           "\"kinematics_error\": %.17g, \"solver_error\": %.17g, \"estimated_error\": %.17g, "
           "\"request_met\": %s, \"error_basis\": \"estimated\", \"summary\": \"%s\"}",
           c->request, c->excitation, c->modes[0], c->modes[1], c->modes[2],
           c->static_correction[0], c->static_correction[1], c->static_correction[2],
           c->exact_kinematics ? "true" : "false", f3r_formulation_name(scene->formulation),
           f3r_integrator_name(scene->integrator), scene->table, scene->rtol, scene->atol,
           c->model_error, c->kinematics_error, c->solver_error, c->estimated_error,
           c->request_met ? "true" : "false", text);
  return p->choice_json;
}

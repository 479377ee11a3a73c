/* Simulated sensors (sensors.h): the exact measurements from a state, then sampling, noise from a
 * counter-based generator, quantisation and a delay line. */
#include "flex3rpr/sensors.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "model_layout.h"
#include "queries.h"
#include "sensor_measures.h"

#define LINE (F3R_SENSOR_MAX_DELAY + 1)

struct f3r_sensors {
  const f3r_model* model;
  int kinds; /* the table's count at creation */
  f3r_sensor_scene config[F3R_SENSOR_MAX_KINDS];
  double constants[F3R_SENSOR_MAX_KINDS][F3R_SENSOR_CONSTANTS];     /* each kind's prepare */
  double line[F3R_SENSOR_MAX_KINDS][LINE][F3R_SENSOR_MAX_CHANNELS]; /* sample k at k % (delay+1) */
  double line_t[F3R_SENSOR_MAX_KINDS][LINE];
  f3r_sensor_reading reading[F3R_SENSOR_MAX_KINDS];
  double last_t;
  double* work; /* f3r_solve_accelerations_work_size */
};

int f3r_sensors_any(const f3r_sensors_scene* c) {
  for (int k = 0; k < F3R_SENSOR_MAX_KINDS; ++k)
    if (c->kind[k].enabled) return 1;
  return 0;
}

f3r_status f3r_sensors_create(const f3r_model* model, const f3r_sensors_scene* config,
                              f3r_sensors** out, f3r_error* err) {
  *out = NULL;
  if (!model || !config) return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_sensors_create: NULL");
  f3r_status st = f3r_sensors_scene_validate(config, err);
  if (st != F3R_OK) return st;
  f3r_sensors* s = calloc(1, sizeof *s);
  if (s) s->work = calloc(f3r_solve_accelerations_work_size(model), sizeof(double));
  if (!s || !s->work) {
    free(s);
    return f3r_error_set(err, F3R_ERR_MEMORY, "f3r_sensors_create: out of memory");
  }
  s->model = model;
  s->kinds = f3r_sensor_kind_count();
  for (int k = 0; k < s->kinds; ++k) {
    s->config[k] = config->kind[k];
    const f3r_sensor_measure* measure = f3r_sensor_measure_of(k);
    if (measure->prepare) measure->prepare(model, s->constants[k]);
  }
  f3r_sensors_reset(s);
  *out = s;
  return F3R_OK;
}

void f3r_sensors_destroy(f3r_sensors* s) {
  if (!s) return;
  free(s->work);
  free(s);
}

void f3r_sensors_reset(f3r_sensors* s) {
  for (int k = 0; k < s->kinds; ++k) {
    f3r_sensor_reading* r = &s->reading[k];
    memset(r, 0, sizeof *r);
    r->enabled = s->config[k].enabled;
    r->channels = f3r_sensor_kind_at(k)->channels;
    r->sample = -1;
    r->updated_at_sample = -1;
  }
  memset(s->line, 0, sizeof s->line);
  memset(s->line_t, 0, sizeof s->line_t);
  s->last_t = -INFINITY;
}

void f3r_sensors_copy(f3r_sensors* to, const f3r_sensors* from) {
  double* work = to->work; /* scratch, its own */
  *to = *from;
  to->work = work;
}

const f3r_sensor_reading* f3r_sensors_reading(const f3r_sensors* s, int kind) {
  return kind >= 0 && kind < s->kinds ? &s->reading[kind] : NULL;
}

int f3r_sensors_columns(const f3r_sensors* s) {
  int n = 0;
  for (int k = 0; k < s->kinds; ++k)
    if (s->reading[k].enabled) n += s->reading[k].channels;
  return n;
}

const char* f3r_sensors_column_name(const f3r_sensors* s, int column) {
  for (int k = 0; k < s->kinds && column >= 0; ++k) {
    if (!s->reading[k].enabled) continue;
    if (column < s->reading[k].channels) return f3r_sensor_kind_at(k)->column[column];
    column -= s->reading[k].channels;
  }
  return NULL;
}

int f3r_sensors_row(const f3r_sensors* s, double* values) {
  int n = 0;
  for (int k = 0; k < s->kinds; ++k)
    for (int c = 0; s->reading[k].enabled && c < s->reading[k].channels; ++c)
      values[n++] = s->reading[k].value[c];
  return n;
}

/* SplitMix64's finaliser: a bijection of 64-bit words that mixes every bit. */
static uint64_t mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/* A uniform in (0, 1) from the top 53 bits of a word. */
static double unit(uint64_t z) { return ((double)(z >> 11) + 0.5) * 0x1.0p-53; }

double f3r_sensor_normal(int seed, int kind, int channel, long sample) {
  const uint64_t stream = mix64((uint64_t)(uint32_t)seed);
  const uint64_t key =
      mix64(stream ^ mix64(((uint64_t)kind << 8 | (uint64_t)channel) ^ mix64((uint64_t)sample)));
  const double u1 = unit(key), u2 = unit(mix64(key));
  return sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2); /* Box-Muller */
}

/* The exact values of the kinds with want[k] into value[k]; the accelerations are solved once,
 * when one of them asks. */
static f3r_status measure_kinds(f3r_sensors* s, const f3r_outputs* out, const int* want,
                                double value[F3R_SENSOR_MAX_KINDS][F3R_SENSOR_MAX_CHANNELS],
                                f3r_error* err) {
  const f3r_model* m = s->model;
  double a[F3R_MAX_Q], lambda[F3R_NCON];
  f3r_sensor_input in = {m, out, NULL, NULL};
  for (int k = 0; k < s->kinds; ++k) {
    if (!want[k]) continue;
    const f3r_sensor_measure* measure = f3r_sensor_measure_of(k);
    if (measure->needs_accelerations && !in.a) {
      if (f3r_solve_accelerations(m, out->q, out->v, out->forces, a, lambda, s->work) != F3R_OK)
        return f3r_error_set(err, F3R_ERR_SINGULAR,
                             "%s: the accelerations cannot be solved at t = %g",
                             f3r_sensor_kind_at(k)->name, out->t);
      in.a = a;
    }
    in.constants = s->constants[k];
    measure->measure(&in, value[k]);
  }
  return F3R_OK;
}

f3r_status f3r_sensors_truth(f3r_sensors* s, const f3r_outputs* out,
                             double value[F3R_SENSOR_MAX_KINDS][F3R_SENSOR_MAX_CHANNELS],
                             f3r_error* err) {
  int want[F3R_SENSOR_MAX_KINDS];
  for (int k = 0; k < s->kinds; ++k) want[k] = 1;
  return measure_kinds(s, out, want, value, err);
}

/* Sample k of sensor kind from the exact values: noise, then quantisation. */
static void measure(f3r_sensors* s, int kind, long k, const double* truth, double t) {
  const f3r_sensor_scene* c = &s->config[kind];
  double* slot = s->line[kind][k % (c->delay + 1)];
  const f3r_sensor_kind* described = f3r_sensor_kind_at(kind);
  for (int ch = 0; ch < described->channels; ++ch) {
    const int g = described->group[ch]; /* which noise[g] and resolution[g] */
    double x = truth[ch];
    if (c->noise[g] > 0.0) x += c->noise[g] * f3r_sensor_normal(c->seed, kind, ch, k);
    if (c->resolution[g] > 0.0) x = c->resolution[g] * nearbyint(x / c->resolution[g]);
    slot[ch] = x;
  }
  s->line_t[kind][k % (c->delay + 1)] = t;
}

/* The newest sample due at t: k / rate <= t, with a millionth of a period for the rounding of
 * output times (0.003 / 0.001 = 2.9999999999999996). */
static long due_sample(double t, double rate) { return (long)floor(t * rate + 1e-6); }

f3r_status f3r_sensors_update(f3r_sensors* s, const f3r_outputs* out, f3r_error* err) {
  if (!(out->t >= s->last_t))
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "f3r_sensors_update: t = %.17g is before the last update's %.17g "
                         "(f3r_sensors_reset first)",
                         out->t, s->last_t);
  double truth[F3R_SENSOR_MAX_KINDS][F3R_SENSOR_MAX_CHANNELS];
  long due[F3R_SENSOR_MAX_KINDS];
  int want[F3R_SENSOR_MAX_KINDS], any = 0;
  for (int kind = 0; kind < s->kinds; ++kind) {
    s->reading[kind].fresh = 0;
    due[kind] = due_sample(out->t, s->config[kind].rate);
    want[kind] = s->config[kind].enabled && due[kind] > s->reading[kind].updated_at_sample;
    any |= want[kind];
  }
  if (!any) {
    s->last_t = out->t;
    return F3R_OK;
  }
  const f3r_status st = measure_kinds(s, out, want, truth, err);
  if (st != F3R_OK) return st;
  for (int kind = 0; kind < s->kinds; ++kind) {
    if (!want[kind]) continue;
    f3r_sensor_reading* r = &s->reading[kind];
    const f3r_sensor_scene* c = &s->config[kind];
    long first = r->updated_at_sample + 1;
    if (first < due[kind] - c->delay) first = due[kind] - c->delay;
    for (long k = first; k <= due[kind]; ++k) measure(s, kind, k, truth[kind], out->t);
    const long reported = due[kind] - c->delay > 0 ? due[kind] - c->delay : 0;
    const int at = (int)(reported % (c->delay + 1));
    memcpy(r->value, s->line[kind][at], sizeof r->value);
    r->measured_at = s->line_t[kind][at];
    r->sample = reported;
    r->updated_at_sample = due[kind];
    r->fresh = 1;
  }
  s->last_t = out->t;
  return F3R_OK;
}

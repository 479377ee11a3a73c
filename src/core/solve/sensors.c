/* Simulated sensors (sensors.h): the exact measurements from a state, then sampling, noise from a
 * counter-based generator, quantisation and a delay line. */
#include "flex3rpr/sensors.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "beam_basis.h"
#include "model_layout.h"
#include "queries.h"

#define LINE (F3R_SENSOR_MAX_DELAY + 1)

struct f3r_sensors {
  const f3r_model* model;
  f3r_sensor_scene config[F3R_SENSOR_KINDS];
  double strain_row[3][F3R_MAX_MODES];
  double line[F3R_SENSOR_KINDS][LINE][F3R_SENSOR_MAX_CHANNELS]; /* sample k at k % (delay+1) */
  double line_t[F3R_SENSOR_KINDS][LINE];
  f3r_sensor_reading reading[F3R_SENSOR_KINDS];
  double last_t;
  double* work; /* f3r_solve_accelerations_work_size */
};

static const int kChannels[F3R_SENSOR_KINDS] = {6, 3, 3};

int f3r_sensors_any(const f3r_sensors_scene* c) {
  return c->encoders.enabled || c->strain_gauges.enabled || c->accelerometer.enabled;
}

int f3r_sensors_strain_row(const f3r_model* m, int link, double* c) {
  const f3r_link_params* lp = &m->link[link];
  if (lp->model == F3R_LINK_RIGID) return 0;
  const double l = m->link_length, half = 0.5 * m->scene.link_diameter;
  for (int j = 0; j < lp->modes; ++j) {
    double dd = 0.0;
    f3r_beam_basis_eval(&m->basis[link], j, 0.0, NULL, NULL, &dd);
    c[j] = half * dd / (l * l);
  }
  return lp->modes;
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
  s->config[F3R_SENSOR_ENCODERS] = config->encoders;
  s->config[F3R_SENSOR_STRAIN] = config->strain_gauges;
  s->config[F3R_SENSOR_ACCELEROMETER] = config->accelerometer;
  for (int i = 0; i < 3; ++i) f3r_sensors_strain_row(model, i, s->strain_row[i]);
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
  for (int k = 0; k < F3R_SENSOR_KINDS; ++k) {
    f3r_sensor_reading* r = &s->reading[k];
    memset(r, 0, sizeof *r);
    r->enabled = s->config[k].enabled;
    r->channels = kChannels[k];
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
  return kind >= 0 && kind < F3R_SENSOR_KINDS ? &s->reading[kind] : NULL;
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

f3r_status f3r_sensors_truth(f3r_sensors* s, const f3r_outputs* out,
                             double value[F3R_SENSOR_KINDS][F3R_SENSOR_MAX_CHANNELS],
                             f3r_error* err) {
  const f3r_model* m = s->model;
  for (int j = 0; j < F3R_Q_LEG_JOINTS; ++j) value[F3R_SENSOR_ENCODERS][j] = out->q[j];
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    double eps = 0.0;
    if (lp->model != F3R_LINK_RIGID)
      for (int j = 0; j < lp->modes; ++j) eps += s->strain_row[i][j] * out->q[lp->eta_index + j];
    value[F3R_SENSOR_STRAIN][i] = eps;
  }
  double a[F3R_MAX_Q], lambda[F3R_NCON];
  if (f3r_solve_accelerations(m, out->q, out->v, out->forces, a, lambda, s->work) != F3R_OK)
    return f3r_error_set(err, F3R_ERR_SINGULAR,
                         "accelerometer: the accelerations cannot be solved at t = %g", out->t);
  const double fx = a[F3R_Q_X] - m->gravity[0], fy = a[F3R_Q_Y] - m->gravity[1];
  const double c = cos(out->q[F3R_Q_PHI]), sn = sin(out->q[F3R_Q_PHI]);
  value[F3R_SENSOR_ACCELEROMETER][0] = c * fx + sn * fy;
  value[F3R_SENSOR_ACCELEROMETER][1] = -sn * fx + c * fy;
  value[F3R_SENSOR_ACCELEROMETER][2] = out->v[F3R_Q_PHI];
  return F3R_OK;
}

/* Sample k of sensor kind from the exact values: noise, then quantisation. */
static void measure(f3r_sensors* s, int kind, long k, const double* truth, double t) {
  const f3r_sensor_scene* c = &s->config[kind];
  double* slot = s->line[kind][k % (c->delay + 1)];
  for (int ch = 0; ch < kChannels[kind]; ++ch) {
    /* noise[g] and resolution[g]: encoders' strokes 0, angles 1; the gyro 1 */
    const int g = kind == F3R_SENSOR_ENCODERS        ? ch / 3
                  : kind == F3R_SENSOR_ACCELEROMETER ? ch == 2
                                                     : 0;
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
  double truth[F3R_SENSOR_KINDS][F3R_SENSOR_MAX_CHANNELS];
  int have_truth = 0;
  for (int kind = 0; kind < F3R_SENSOR_KINDS; ++kind) {
    f3r_sensor_reading* r = &s->reading[kind];
    const f3r_sensor_scene* c = &s->config[kind];
    r->fresh = 0;
    if (!c->enabled) continue;
    const long due = due_sample(out->t, c->rate);
    if (due <= r->updated_at_sample) continue;
    if (!have_truth) {
      const f3r_status st = f3r_sensors_truth(s, out, truth, err);
      if (st != F3R_OK) return st;
      have_truth = 1;
    }
    long first = r->updated_at_sample + 1;
    if (first < due - c->delay) first = due - c->delay;
    for (long k = first; k <= due; ++k) measure(s, kind, k, truth[kind], out->t);
    const long reported = due - c->delay > 0 ? due - c->delay : 0;
    const int at = (int)(reported % (c->delay + 1));
    memcpy(r->value, s->line[kind][at], sizeof r->value);
    r->measured_at = s->line_t[kind][at];
    r->sample = reported;
    r->updated_at_sample = due;
    r->fresh = 1;
  }
  s->last_t = out->t;
  return F3R_OK;
}

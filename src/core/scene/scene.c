/* Scene defaults (Table I, docs/model.md), range checks and scripted inputs. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flex3rpr/kinds.h"
#include "flex3rpr/scene.h"
#include "names.h"

f3r_scene f3r_default_scene(void) {
  f3r_scene s;
  memset(&s, 0, sizeof s);
  s.base_side = 0.66;
  s.platform_side = 0.1;
  s.platform_mass = 0.2;
  s.platform_inertia = 0.0; /* 0: uniform thin triangular plate, m_p b^2 / 12 */
  s.link_length = 0.2;
  s.link_diameter = 0.010;
  s.link_density = 2270.0;
  s.link_youngs_modulus = 73e9;
  s.cylinder_length = 0.2;
  s.cylinder_inner_diameter = 0.014;
  s.cylinder_outer_diameter = 0.016;
  s.cylinder_density = 2270.0;
  for (int i = 0; i < 3; ++i) {
    s.links[i].model = F3R_LINK_RIGID;
    s.links[i].auto_tolerance = 1e-3;
  }
  s.gravity[2] = -9.81;
  s.stroke_min = 0.0;
  s.stroke_max = 0.2;
  s.restitution = 0.5;
  s.formulation = F3R_FORMULATION_MINIMAL; /* measured 2-3x faster than dae at equal accuracy */
  /* The cheapest solver at 6 correct digits on paper simulation 3 (bench/work_precision, 2026-11-23):
   * minimal on IDA at rtol 2.2e-7..4.6e-7, 6.1 digits at a real-time factor of 2.8-3.1, ahead of
   * Dormand-Prince 5(4) at 1e-5 (6.0 digits, 3.0) and Fehlberg 7(8) at 3e-4 (6.1, 2.6). */
  s.rtol = 2e-7;
  s.max_order = 5;
  s.atol = 2e-9;
  s.accuracy_verify = 1;
  s.accuracy_escalations = 3;
  s.limit_force = 1000.0;
  s.limit_torque = 100.0;
  s.limit_modal_force = 1000.0;
  s.duration = 0.5;
  s.output_step = 1e-4;
  s.beam_points = 11;
  return s;
}

static const char* const kInputNames[F3R_RIGID_FORCES] = {"rho_1",
                                                          "rho_2",
                                                          "rho_3",
                                                          "theta_1",
                                                          "theta_2",
                                                          "theta_3",
                                                          "platform_force_x",
                                                          "platform_force_y",
                                                          "platform_torque"};

const char* f3r_input_name(int index) {
  return index >= 0 && index < F3R_RIGID_FORCES ? kInputNames[index] : "unknown";
}

double f3r_input_value(const f3r_input* in, double t) {
  switch (in->kind) {
    case F3R_INPUT_NONE: return 0.0;
    case F3R_INPUT_CONSTANT: return in->offset;
    case F3R_INPUT_HARMONIC: return in->offset + in->amplitude * cos(in->omega * t + in->phase);
    case F3R_INPUT_STEP: return t <= in->t0 ? in->before : in->after;
    case F3R_INPUT_RAMP:
      if (t <= in->t0) return in->before;
      if (t >= in->t1) return in->after;
      return in->before + (in->after - in->before) * (t - in->t0) / (in->t1 - in->t0);
    case F3R_INPUT_CHIRP: {
      if (t < in->t0 || t > in->t1) return in->offset;
      const double tau = t - in->t0, span = in->t1 - in->t0;
      const double cycles = in->f0 * tau + 0.5 * (in->f1 - in->f0) * tau * tau / span;
      return in->offset + in->amplitude * sin(2.0 * M_PI * cycles);
    }
    case F3R_INPUT_TABLE: {
      const int n = in->table_size;
      if (t <= in->table_time[0]) return in->table_value[0];
      if (t >= in->table_time[n - 1]) return in->table_value[n - 1];
      /* the first k >= 1 with time[k] >= t, by bisection: a residual evaluation costs
       * log2(n) comparisons, not n, and the input stays free of a cursor's state */
      int k = 1, hi = n - 1;
      while (k < hi) {
        const int mid = k + (hi - k) / 2;
        if (in->table_time[mid] < t)
          k = mid + 1;
        else
          hi = mid;
      }
      if (in->table_hold) return in->table_value[k - 1];
      const double w = (t - in->table_time[k - 1]) / (in->table_time[k] - in->table_time[k - 1]);
      return in->table_value[k - 1] + w * (in->table_value[k] - in->table_value[k - 1]);
    }
  }
  return 0.0;
}

double f3r_input_max_frequency(const f3r_input* in) {
  if (in->kind == F3R_INPUT_HARMONIC && in->amplitude != 0.0) return fabs(in->omega) / (2.0 * M_PI);
  if (in->kind == F3R_INPUT_CHIRP && in->amplitude != 0.0) return fmax(in->f0, in->f1);
  return 0.0;
}

int f3r_input_breakpoints(const f3r_input* in, double* times, int max) {
  int n = 0;
  switch (in->kind) {
    case F3R_INPUT_STEP:
      if (n < max) times[n++] = in->t0;
      break;
    case F3R_INPUT_RAMP:
    case F3R_INPUT_CHIRP:
      if (n < max) times[n++] = in->t0;
      if (n < max) times[n++] = in->t1;
      break;
    case F3R_INPUT_TABLE:
      for (int k = 0; k < in->table_size && n < max; ++k) times[n++] = in->table_time[k];
      break;
    default: break;
  }
  return n;
}

/* A table's entries, or 0 for an input without one (or a size out of range). */
static size_t table_entries(const f3r_input* in) {
  const int ok = in->table_time && in->table_value && in->table_size > 0;
  return ok ? (size_t)in->table_size : 0;
}

void f3r_scene_free(f3r_scene* scene) {
  if (!scene) return;
  for (int k = 0; k < F3R_RIGID_FORCES; ++k) {
    f3r_input* in = &scene->inputs[k];
    free(in->table_time); /* the block of both lists */
    in->table_time = in->table_value = NULL;
    in->table_size = 0;
    if (in->kind == F3R_INPUT_TABLE) in->kind = F3R_INPUT_NONE;
  }
}

size_t f3r_scene_table_doubles(const f3r_scene* src) {
  size_t n = 0;
  for (int k = 0; k < F3R_RIGID_FORCES; ++k) n += 2 * table_entries(&src->inputs[k]);
  return n;
}

/* Points in's table at storage (2 * n doubles) and copies from's entries there. */
static void place_table(f3r_input* in, const f3r_input* from, double* storage, size_t n) {
  in->table_time = storage;
  in->table_value = storage + n;
  memcpy(in->table_time, from->table_time, n * sizeof(double));
  memcpy(in->table_value, from->table_value, n * sizeof(double));
}

void f3r_scene_copy_into(f3r_scene* dst, const f3r_scene* src, double* storage) {
  *dst = *src;
  for (int k = 0; k < F3R_RIGID_FORCES; ++k) {
    const size_t n = table_entries(&src->inputs[k]);
    dst->inputs[k].table_time = dst->inputs[k].table_value = NULL;
    if (!n) continue;
    place_table(&dst->inputs[k], &src->inputs[k], storage, n);
    storage += 2 * n;
  }
}

f3r_status f3r_scene_copy(f3r_scene* dst, const f3r_scene* src, f3r_error* err) {
  if (!dst || !src) return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_scene_copy: NULL argument");
  *dst = *src;
  for (int k = 0; k < F3R_RIGID_FORCES; ++k)
    dst->inputs[k].table_time = dst->inputs[k].table_value = NULL; /* src's, until copied */
  for (int k = 0; k < F3R_RIGID_FORCES; ++k) {
    const size_t n = table_entries(&src->inputs[k]);
    if (!n) continue;
    double* block = malloc(2 * n * sizeof(double));
    if (!block) {
      f3r_scene_free(dst);
      return f3r_error_set(err, F3R_ERR_MEMORY, "f3r_scene_copy: out of memory");
    }
    place_table(&dst->inputs[k], &src->inputs[k], block, n);
  }
  return F3R_OK;
}

f3r_status f3r_input_set_table(f3r_input* in, const double* time, const double* value, int size,
                               int hold, f3r_error* err) {
  if (!in || !time || !value)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_input_set_table: NULL argument");
  if (size < 2 || size > F3R_MAX_TABLE)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_input_set_table: %d entries, allowed 2..%d",
                         size, F3R_MAX_TABLE);
  double* block = malloc(2 * (size_t)size * sizeof(double));
  if (!block) return f3r_error_set(err, F3R_ERR_MEMORY, "f3r_input_set_table: out of memory");
  const f3r_input from = {.table_time = (double*)time, .table_value = (double*)value};
  free(in->table_time);
  place_table(in, &from, block, (size_t)size);
  in->table_size = size;
  in->table_hold = hold;
  in->kind = F3R_INPUT_TABLE;
  return F3R_OK;
}

#define CHECK_RANGE(field, value, lo, hi)                                                     \
  do {                                                                                        \
    const double v_ = (value);                                                                \
    if (!(v_ >= (lo) && v_ <= (hi)))                                                          \
      return f3r_scene_error(err, field, NULL, "%g is out of range %g..%g", v_, (double)(lo), \
                             (double)(hi));                                                   \
  } while (0)

#define CHECK_POSITIVE(field, value)                                                  \
  do {                                                                                \
    const double v_ = (value);                                                        \
    if (!(v_ > 0.0 && isfinite(v_)))                                                  \
      return f3r_scene_error(err, field, NULL, "%g must be positive and finite", v_); \
  } while (0)

/* CHECK_RANGE for a field named by a format (in `name`), formatted only when the check fails:
 * models are built per pilot and per linear estimate, and 130 names formatted for every valid
 * scene cost a fifth of building a stiff_high_modes model. */
#define CHECK_RANGE_AT(value, lo, hi, ...)      \
  do {                                          \
    const double w_ = (value);                  \
    if (!(w_ >= (lo) && w_ <= (hi))) {          \
      snprintf(name, sizeof name, __VA_ARGS__); \
      CHECK_RANGE(name, w_, lo, hi);            \
    }                                           \
  } while (0)

#define CHECK_FINITE(field, value)                                                                \
  do {                                                                                            \
    if (!isfinite(value)) return f3r_scene_error(err, field, NULL, "%g must be finite", (value)); \
  } while (0)

static f3r_status validate_input_shape(const f3r_input* in, const char* name, f3r_error* err) {
  char field[96];
  switch (in->kind) {
    case F3R_INPUT_STEP:
      snprintf(field, sizeof field, "%s.step.time", name);
      CHECK_RANGE(field, in->t0, 0.0, 1e6);
      break;
    case F3R_INPUT_RAMP:
    case F3R_INPUT_CHIRP: {
      const char* kind = in->kind == F3R_INPUT_RAMP ? "ramp" : "chirp";
      snprintf(field, sizeof field, "%s.%s.start", name, kind);
      CHECK_RANGE(field, in->t0, 0.0, 1e6);
      if (!(in->t1 > in->t0)) {
        snprintf(field, sizeof field, "%s.%s.end", name, kind);
        return f3r_scene_error(err, field, NULL, "%g must be after start %g", in->t1, in->t0);
      }
      if (in->kind == F3R_INPUT_CHIRP) {
        snprintf(field, sizeof field, "%s.chirp.start_frequency", name);
        CHECK_RANGE(field, in->f0, 0.0, 1e6);
        if (!(in->f1 >= in->f0)) {
          snprintf(field, sizeof field, "%s.chirp.end_frequency", name);
          return f3r_scene_error(err, field, NULL, "%g Hz is below start_frequency %g Hz", in->f1,
                                 in->f0);
        }
      }
      break;
    }
    case F3R_INPUT_TABLE: {
      char list[96];
      snprintf(list, sizeof list, "%s.table", name);
      if (in->table_size < 2 || in->table_size > F3R_MAX_TABLE)
        return f3r_scene_error(err, list, NULL, "%d points, allowed 2..%d", in->table_size,
                               F3R_MAX_TABLE);
      if (!in->table_time || !in->table_value)
        return f3r_scene_error(err, list, NULL, "%d points but no lists (f3r_input_set_table)",
                               in->table_size);
      for (int k = 0; k < in->table_size; ++k) {
        const int bad_time = !isfinite(in->table_time[k]);
        if (bad_time || !isfinite(in->table_value[k])) {
          snprintf(field, sizeof field, "%s.%s[%d]", list, bad_time ? "time" : "value", k);
          return f3r_scene_error(err, field, list, "point %d is not finite", k);
        }
        if (k > 0 && !(in->table_time[k] > in->table_time[k - 1])) {
          char times[112];
          snprintf(times, sizeof times, "%s.time", list);
          snprintf(field, sizeof field, "%s[%d]", times, k);
          return f3r_scene_error(err, field, times, "%g at point %d must exceed %g before it",
                                 in->table_time[k], k, in->table_time[k - 1]);
        }
      }
      break;
    }
    default: break;
  }
  return F3R_OK;
}

const char* const* f3r_rk_tables(f3r_integrator integrator) {
  const f3r_integrator_kind* kind = f3r_integrator_kind_at((int)integrator);
  return kind ? kind->tables : NULL;
}

static int table_known(f3r_integrator integrator, const char* name) {
  const char* const* t = f3r_rk_tables(integrator);
  for (; t && *t; ++t)
    if (!strcmp(*t, name)) return 1;
  return 0;
}

/* The geometry and the bodies' dimensions and densities. */
static f3r_status validate_bodies(const f3r_scene* s, f3r_error* err) {
  CHECK_POSITIVE("geometry.base_side", s->base_side);
  CHECK_POSITIVE("geometry.platform_side", s->platform_side);
  if (!(s->platform_side < s->base_side))
    return f3r_scene_error(err, "geometry.platform_side", NULL,
                           "%g must be smaller than base_side %g", s->platform_side, s->base_side);
  CHECK_POSITIVE("platform.mass", s->platform_mass);
  CHECK_RANGE("platform.inertia", s->platform_inertia, 0.0, 1e6);
  CHECK_POSITIVE("link.length", s->link_length);
  CHECK_POSITIVE("link.diameter", s->link_diameter);
  CHECK_POSITIVE("link.density", s->link_density);
  CHECK_POSITIVE("link.youngs_modulus", s->link_youngs_modulus);
  CHECK_POSITIVE("cylinder.length", s->cylinder_length);
  CHECK_RANGE("cylinder.inner_diameter", s->cylinder_inner_diameter, 0.0, 1e3);
  CHECK_POSITIVE("cylinder.outer_diameter", s->cylinder_outer_diameter);
  if (!(s->cylinder_inner_diameter < s->cylinder_outer_diameter))
    return f3r_scene_error(err, "cylinder.inner_diameter", NULL,
                           "%g must be smaller than outer_diameter %g", s->cylinder_inner_diameter,
                           s->cylinder_outer_diameter);
  CHECK_POSITIVE("cylinder.density", s->cylinder_density);
  return F3R_OK;
}

int f3r_link_static_shapes(f3r_link_model model) {
  /* model.c, correction_shapes: tip force and uniform load; a pin's uniform and linear load */
  return model == F3R_LINK_FIXED_FREE ? 2 : model == F3R_LINK_FIXED_PINNED ? 2 : 0;
}

int f3r_link_correction_functions(const f3r_link_scene* L) {
  if (L->model == F3R_LINK_RIGID || !L->static_correction) return 0;
  return L->shape_mix_kind == F3R_SHAPE_PAIR ? f3r_link_static_shapes(L->model) : 1;
}

int f3r_link_scene_functions(const f3r_link_scene* L) {
  return L->model == F3R_LINK_RIGID ? 0 : L->modes + f3r_link_correction_functions(L);
}

/* links[i].shape_mix: one mixed shape stands for a fixed-free link's pair. */
static f3r_status validate_shape_mix(const f3r_link_scene* L, int i, f3r_error* err) {
  char name[64];
  snprintf(name, sizeof name, "links[%d].shape_mix", i);
  if (L->shape_mix_kind == F3R_SHAPE_PAIR) return F3R_OK;
  if (L->shape_mix_kind != F3R_SHAPE_MIXED && L->shape_mix_kind != F3R_SHAPE_MIX_FIT)
    return f3r_scene_error(err, name, NULL, "kind %d is not a number or fit",
                           (int)L->shape_mix_kind);
  if (L->model != F3R_LINK_FIXED_FREE || !L->static_correction)
    return f3r_scene_error(err, name, NULL,
                           "given for a link without the fixed-free static correction (allowed "
                           "with model fixed_free and static_correction true)");
  if (L->shape_mix_kind == F3R_SHAPE_MIXED)
    CHECK_RANGE(name, L->shape_mix, -F3R_SHAPE_MIX_LIMIT, F3R_SHAPE_MIX_LIMIT);
  return F3R_OK;
}

/* links[i].static_correction: a flexible link with a number of modes that leaves room for the
 * shapes. */
static f3r_status validate_static_correction(const f3r_scene* s, int i, f3r_error* err) {
  char name[64];
  const f3r_link_scene* L = &s->links[i];
  if (!L->static_correction) return F3R_OK;
  snprintf(name, sizeof name, "links[%d].static_correction", i);
  if (L->static_correction != 1)
    return f3r_scene_error(err, name, NULL, "%d is not true or false", L->static_correction);
  if (L->model == F3R_LINK_RIGID)
    return f3r_scene_error(err, name, NULL,
                           "true given for a rigid link, which has no modes (allowed with "
                           "model fixed_free or fixed_pinned)");
  const int shapes = f3r_link_correction_functions(L);
  /* open modes (auto, or left to the accuracy knob): the search adds the shapes to its counts */
  if (L->modes + shapes > F3R_MAX_MODES) {
    snprintf(name, sizeof name, "links[%d].modes", i);
    return f3r_scene_error(err, name, NULL,
                           "%d with static_correction adds %d shapes, %d functions: allowed "
                           "1..%d modes (at most %d functions)",
                           L->modes, shapes, L->modes + shapes, F3R_MAX_MODES - shapes,
                           F3R_MAX_MODES);
  }
  return F3R_OK;
}

/* Link i's model, its mode count and its initial modal state. */
static f3r_status validate_link(const f3r_scene* s, int i, f3r_error* err) {
  char name[64];
  const f3r_link_scene* L = &s->links[i];
  snprintf(name, sizeof name, "links[%d].model", i);
  if (L->model != F3R_LINK_RIGID && L->model != F3R_LINK_FIXED_PINNED &&
      L->model != F3R_LINK_FIXED_FREE)
    return f3r_scene_error(err, name, NULL, "%d is not one of rigid, fixed_pinned, fixed_free",
                           (int)L->model);
  snprintf(name, sizeof name, "links[%d].modes", i);
  if (L->model == F3R_LINK_RIGID) {
    if (L->modes != 0)
      return f3r_scene_error(err, name, NULL, "%d given for a rigid link, which has no modes",
                             L->modes);
  } else if (L->modes == F3R_MODES_AUTO) {
    snprintf(name, sizeof name, "links[%d].auto_tolerance", i);
    CHECK_RANGE(name, L->auto_tolerance, 1e-12, 0.5);
  } else if (L->modes == 0 && s->accuracy > 0.0) {
    /* left to the accuracy knob */
  } else if (L->modes < 1 || L->modes > F3R_MAX_MODES) {
    return f3r_scene_error(err, name, NULL, "%d is out of range 1..%d", L->modes, F3R_MAX_MODES);
  }
  f3r_status st = validate_static_correction(s, i, err);
  if (st == F3R_OK) st = validate_shape_mix(L, i, err);
  if (st != F3R_OK) return st;
  const int functions = f3r_link_scene_functions(L);
  for (int j = 0; j < F3R_MAX_MODES; ++j) {
    CHECK_RANGE_AT(L->eta0[j], -F3R_STATE_MODAL_LIMIT, F3R_STATE_MODAL_LIMIT,
                   "links[%d].initial_deflection[%d]", i, j);
    CHECK_RANGE_AT(L->eta_rate0[j], -F3R_STATE_MODAL_RATE_LIMIT, F3R_STATE_MODAL_RATE_LIMIT,
                   "links[%d].initial_rate[%d]", i, j);
    const int open = L->modes == F3R_MODES_AUTO || (L->modes == 0 && L->model != F3R_LINK_RIGID);
    if (!open && j >= functions && (L->eta0[j] != 0.0 || L->eta_rate0[j] != 0.0)) {
      char list[64];
      snprintf(list, sizeof list, "links[%d].initial_deflection", i);
      snprintf(name, sizeof name, "%s[%d]", list, j);
      if (functions > L->modes)
        return f3r_scene_error(err, name, list,
                               "function %d given but the link has %d functions (%d mode%s + "
                               "%d static shapes)",
                               j + 1, functions, L->modes, L->modes == 1 ? "" : "s",
                               functions - L->modes);
      return f3r_scene_error(err, name, list, "mode %d given but the link has %d modes", j + 1,
                             L->modes);
    }
  }
  return F3R_OK;
}

/* The effects (gravity, friction, damping, actuator lag, end stops, payload) and the initial
 * platform pose and velocity. */
static f3r_status validate_effects_and_pose(const f3r_scene* s, f3r_error* err) {
  char name[64];
  for (int k = 0; k < 3; ++k) {
    CHECK_RANGE_AT(s->gravity[k], -1e3, 1e3, "effects.gravity[%d]", k);
    CHECK_RANGE_AT(s->friction_prismatic[k], 0.0, 1e6, "effects.joint_friction.prismatic[%d]", k);
    CHECK_RANGE_AT(s->friction_revolute[k], 0.0, 1e6, "effects.joint_friction.revolute[%d]", k);
    CHECK_RANGE_AT(s->links[k].damping_ratio, 0.0, 10.0, "links[%d].damping_ratio", k);
    if (s->links[k].model == F3R_LINK_RIGID && s->links[k].damping_ratio != 0.0) {
      snprintf(name, sizeof name, "links[%d].damping_ratio", k);
      return f3r_scene_error(err, name, NULL, "%g given for a rigid link, which has no modes",
                             s->links[k].damping_ratio);
    }
  }
  CHECK_RANGE("effects.actuator_lag.time_constant", s->actuator_lag, 0.0, 10.0);
  CHECK_RANGE("effects.end_stops.restitution", s->restitution, 0.0, 1.0);
  /* The stroke is the prismatic joints' range (the URDF's limits); end stops make it hard. */
  CHECK_RANGE(s->end_stops ? "effects.end_stops.min" : "geometry.stroke_min", s->stroke_min,
              -s->link_length + 1e-3, 10.0);
  if (!(s->stroke_max > s->stroke_min))
    return f3r_scene_error(err, s->end_stops ? "effects.end_stops.max" : "geometry.stroke_max",
                           NULL, "%g must exceed the minimum %g", s->stroke_max, s->stroke_min);
  CHECK_RANGE("effects.payload.mass", s->payload_mass, 0.0, 1e3);
  CHECK_RANGE("effects.payload.inertia", s->payload_inertia, 0.0, 1e3);
  for (int k = 0; k < 3; ++k) {
    const double limit = k < 2 ? F3R_STATE_POSITION_LIMIT : F3R_STATE_ANGLE_LIMIT;
    CHECK_RANGE_AT(s->platform_pose0[k], -limit, limit, "initial.platform_pose[%d]", k);
    CHECK_RANGE_AT(s->platform_velocity0[k], -F3R_STATE_RATE_LIMIT, F3R_STATE_RATE_LIMIT,
                   "initial.platform_velocity[%d]", k);
  }
  return F3R_OK;
}

/* Every scripted input: a known kind, finite parameters and a well-formed shape. */
static f3r_status validate_inputs(const f3r_scene* s, f3r_error* err) {
  char name[64];
  for (int n = 0; n < F3R_RIGID_FORCES; ++n) {
    const f3r_input* in = &s->inputs[n];
    snprintf(name, sizeof name, "inputs.%s", kInputNames[n]);
    if ((int)in->kind < F3R_INPUT_NONE || (int)in->kind > F3R_INPUT_TABLE)
      return f3r_scene_error(err, name, NULL, "kind %d is not a known input kind", (int)in->kind);
    const double values[] = {in->offset, in->amplitude, in->omega, in->phase, in->t0,
                             in->t1,     in->before,    in->after, in->f0,    in->f1};
    for (size_t k = 0; k < sizeof values / sizeof values[0]; ++k) CHECK_FINITE(name, values[k]);
    f3r_status st = validate_input_shape(in, name, err);
    if (st != F3R_OK) return st;
  }
  return F3R_OK;
}

/* The solver (formulation, integrator, Butcher table, tolerances), the accuracy request and the
 * run's duration and output. */
static f3r_status validate_solver_and_run(const f3r_scene* s, f3r_error* err) {
  if (s->formulation != F3R_FORMULATION_DAE && s->formulation != F3R_FORMULATION_MINIMAL)
    return f3r_scene_error(err, "solver.formulation", NULL, "%d is not one of dae, minimal",
                           (int)s->formulation);
  const f3r_integrator_kind* kind = f3r_integrator_kind_at((int)s->integrator);
  if (!kind) {
    char allowed[256];
    return f3r_scene_error(err, "solver.integrator", NULL, "%d is not one of %s",
                           (int)s->integrator, f3r_integrator_names(allowed, sizeof allowed));
  }
  if (!(kind->formulations & (1u << s->formulation)))
    return f3r_scene_error(err, "solver.integrator", NULL, "%s integrates the %s formulation only",
                           kind->name,
                           f3r_formulation_name(kind->formulations & (1u << F3R_FORMULATION_DAE)
                                                    ? F3R_FORMULATION_DAE
                                                    : F3R_FORMULATION_MINIMAL));
  if (s->table[0] && !kind->tables) {
    const char* names[F3R_INTEGRATOR_MAX_KINDS];
    int count = 0;
    for (int k = 0; k < f3r_integrator_kind_count(); ++k)
      if (f3r_integrator_kind_at(k)->tables) names[count++] = f3r_integrator_kind_at(k)->name;
    char with_tables[256];
    return f3r_scene_error(err, "solver.table", NULL, "a Butcher table needs integrator %s",
                           f3r_join_names(names, count, " or ", with_tables, sizeof with_tables));
  }
  if (s->table[0] && !table_known(s->integrator, s->table)) {
    char allowed[512] = "";
    for (const char* const* t = f3r_rk_tables(s->integrator); *t; ++t)
      snprintf(allowed + strlen(allowed), sizeof allowed - strlen(allowed), "%s%s",
               allowed[0] ? ", " : "", *t);
    return f3r_scene_error(err, "solver.table", NULL, "'%s' is not one of %s", s->table, allowed);
  }
  CHECK_RANGE("solver.rtol", s->rtol, 1e-14, 1e-1);
  if (s->accuracy != 0.0) CHECK_RANGE("accuracy.end_effector", s->accuracy, 1e-9, 1.0);
  if (s->accuracy_escalations < 0 || s->accuracy_escalations > F3R_ACCURACY_MAX_ESCALATIONS)
    return f3r_scene_error(err, "accuracy.escalations", NULL, "%d is out of range 0..%d",
                           s->accuracy_escalations, F3R_ACCURACY_MAX_ESCALATIONS);
  if (s->accuracy_excitation != 0.0)
    CHECK_RANGE("accuracy.excitation", s->accuracy_excitation, 1e-6, 1e9);
  CHECK_RANGE("solver.atol", s->atol, 1e-16, 1e-1);
  CHECK_RANGE("solver.max_step", s->max_step, 0.0, 1e3);
  if (s->max_order < 1 || s->max_order > 5)
    return f3r_scene_error(err, "solver.max_order", NULL, "%d is out of range 1..5", s->max_order);
  CHECK_RANGE("limits.force", s->limit_force, 1e-6, 1e9);
  CHECK_RANGE("limits.torque", s->limit_torque, 1e-6, 1e9);
  CHECK_RANGE("limits.modal_force", s->limit_modal_force, 1e-6, 1e9);
  CHECK_RANGE("run.duration", s->duration, 0.0, 1e6);
  CHECK_RANGE("run.output_step", s->output_step, 1e-7, 1e3);
  if ((double)s->beam_points < 2 || s->beam_points > 101)
    return f3r_scene_error(err, "run.beam_points", NULL, "%d is out of range 2..101",
                           s->beam_points);
  return F3R_OK;
}

/* Section by section; the first error found is the one reported. */
f3r_status f3r_scene_validate(const f3r_scene* s, f3r_error* err) {
  f3r_status st = validate_bodies(s, err);
  for (int i = 0; st == F3R_OK && i < 3; ++i) st = validate_link(s, i, err);
  if (st == F3R_OK) st = validate_effects_and_pose(s, err);
  if (st == F3R_OK) st = validate_inputs(s, err);
  if (st == F3R_OK) st = validate_solver_and_run(s, err);
  if (st == F3R_OK) st = f3r_sensors_scene_validate(&s->sensors, err);
  return st;
}

/* The sensor kinds (kinds.h): one row each, the only list of them. Their measurements are the
 * solve layer's (src/core/solve/sensor_measures.c), in the same order. */
#include <string.h>

#include "flex3rpr/kinds.h"
#include "names.h"

static const f3r_sensor_kind kBuiltin[] = {
    {"encoders",
     "sensors/encoders",
     "rho_i (m) and theta_i (rad) of the three legs",
     6,
     {"enc_rho_1", "enc_rho_2", "enc_rho_3", "enc_theta_1", "enc_theta_2", "enc_theta_3"},
     {"leg_1_prismatic", "leg_2_prismatic", "leg_3_prismatic", "leg_1_revolute", "leg_2_revolute",
      "leg_3_revolute"},
     {"stroke_noise", "angle_noise"},
     {"stroke_resolution", "angle_resolution"},
     {0, 0, 0, 1, 1, 1}},
    {"strain_gauges",
     "sensors/strain",
     "the bending strain at each beam's root",
     3,
     {"strain_1", "strain_2", "strain_3"},
     {NULL},
     {"noise", NULL},
     {"resolution", NULL},
     {0, 0, 0}},
    {"accelerometer",
     "sensors/accelerometer",
     "the platform's specific force (m/s^2, platform frame) and angular rate (rad/s)",
     3,
     {"accel_x", "accel_y", "gyro_z"},
     {NULL},
     {"noise", "gyro_noise"},
     {"resolution", "gyro_resolution"},
     {0, 0, 1}}};

#define BUILTIN ((int)(sizeof kBuiltin / sizeof kBuiltin[0]))

static const f3r_sensor_kind* added[F3R_SENSOR_MAX_KINDS];
static int added_count;

int f3r_sensor_kind_count(void) { return BUILTIN + added_count; }

const f3r_sensor_kind* f3r_sensor_kind_at(int k) {
  if (k >= 0 && k < BUILTIN) return &kBuiltin[k];
  if (k >= BUILTIN && k < BUILTIN + added_count) return added[k - BUILTIN];
  return NULL;
}

int f3r_sensor_kind_find(const char* name) {
  for (int k = 0; name && k < f3r_sensor_kind_count(); ++k)
    if (!strcmp(f3r_sensor_kind_at(k)->name, name)) return k;
  return -1;
}

const char* f3r_sensor_kind_names(char* list, size_t size) {
  const char* names[F3R_SENSOR_MAX_KINDS];
  for (int k = 0; k < f3r_sensor_kind_count(); ++k) names[k] = f3r_sensor_kind_at(k)->name;
  return f3r_join_names(names, f3r_sensor_kind_count(), ", ", list, size);
}

int f3r_sensor_kind_add(const f3r_sensor_kind* kind) {
  if (!kind || !kind->name || !kind->topic || kind->channels < 1 ||
      kind->channels > F3R_SENSOR_MAX_CHANNELS || f3r_sensor_kind_find(kind->name) >= 0 ||
      f3r_sensor_kind_count() >= F3R_SENSOR_MAX_KINDS)
    return -1;
  for (int c = 0; c < kind->channels; ++c)
    if (!kind->column[c] || kind->group[c] > 1 || !kind->noise_key[kind->group[c]]) return -1;
  added[added_count++] = kind;
  return f3r_sensor_kind_count() - 1;
}

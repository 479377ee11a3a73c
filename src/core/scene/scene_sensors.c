/* The scene's sensors section: defaults, YAML keys and range checks (docs/scenes.md, sensors).
 *
 *   sensors:
 *     encoders:      {rate, delay, seed, stroke_noise, angle_noise, stroke_resolution,
 *                     angle_resolution, enabled}
 *     strain_gauges: {rate, delay, seed, noise, resolution, enabled}
 *     accelerometer: {rate, delay, seed, noise, gyro_noise, resolution, gyro_resolution,
 *                     enabled}
 *
 * A sensor named in the file is enabled unless it says enabled: false. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <yaml.h>

#include "flex3rpr/scene.h"
#include "scene_yaml_reader.h"

void f3r_sensor_scene_defaults(f3r_sensor_scene* s) {
  memset(s, 0, sizeof *s);
  s->enabled = 1;
  s->rate = 1000.0;
  s->seed = 1;
}

/* The keys of one sensor: the names of noise[0], noise[1], resolution[0], resolution[1] (NULL
 * where the sensor has no such channel kind). */
typedef struct {
  const char* name;
  const char* keys[4];
} sensor_keys;

static const sensor_keys kSensors[3] = {
    {"encoders", {"stroke_noise", "angle_noise", "stroke_resolution", "angle_resolution"}},
    {"strain_gauges", {"noise", NULL, "resolution", NULL}},
    {"accelerometer", {"noise", "gyro_noise", "resolution", "gyro_resolution"}}};

static f3r_sensor_scene* sensor_of(f3r_sensors_scene* s, int k) {
  return k == 0 ? &s->encoders : k == 1 ? &s->strain_gauges : &s->accelerometer;
}

static f3r_status read_sensor(loader* L, const yaml_node_t* map, int k) {
  char section[64];
  snprintf(section, sizeof section, "sensors.%s", kSensors[k].name);
  f3r_status st = f3r_yaml_mapping(L, map, section);
  if (st != F3R_OK) return st;
  f3r_yaml_remember(L, section, map);
  f3r_sensor_scene* s = sensor_of(&L->scene->sensors, k);
  f3r_sensor_scene_defaults(s);
  FOR_EACH_PAIR(L, map, key, value) {
    char name[128];
    snprintf(name, sizeof name, "%s.%s", section, key);
    double* target = NULL;
    for (int j = 0; j < 4; ++j)
      if (kSensors[k].keys[j] && !strcmp(key, kSensors[k].keys[j]))
        target = j < 2 ? &s->noise[j] : &s->resolution[j - 2];
    if (target)
      st = f3r_yaml_number(L, value, name, target);
    else if (!strcmp(key, "rate"))
      st = f3r_yaml_number(L, value, name, &s->rate);
    else if (!strcmp(key, "delay"))
      st = f3r_yaml_int(L, value, name, &s->delay);
    else if (!strcmp(key, "seed"))
      st = f3r_yaml_int(L, value, name, &s->seed);
    else if (!strcmp(key, "enabled"))
      st = f3r_yaml_bool(L, value, name, &s->enabled);
    else {
      char allowed[160] = "enabled, rate, delay, seed";
      for (int j = 0; j < 4; ++j)
        if (kSensors[k].keys[j])
          snprintf(allowed + strlen(allowed), sizeof allowed - strlen(allowed), ", %s",
                   kSensors[k].keys[j]);
      st = f3r_yaml_fail(L, value, name, "unknown key (allowed: %s)", allowed);
    }
    if (st != F3R_OK) return st;
  }
  return F3R_OK;
}

f3r_status f3r_yaml_read_sensors(loader* L, const yaml_node_t* map) {
  f3r_status st = f3r_yaml_mapping(L, map, "sensors");
  if (st != F3R_OK) return st;
  f3r_yaml_remember(L, "sensors", map);
  FOR_EACH_PAIR(L, map, key, value) {
    int k = 0;
    while (k < 3 && strcmp(key, kSensors[k].name)) ++k;
    if (k == 3) {
      char name[96];
      snprintf(name, sizeof name, "sensors.%s", key);
      return f3r_yaml_fail(L, value, name,
                           "unknown sensor (allowed: encoders, strain_gauges, accelerometer)");
    }
    if ((st = read_sensor(L, value, k)) != F3R_OK) return st;
  }
  return F3R_OK;
}

/* "sensors.encoders.stroke_noise" for noise[0] of sensor k, into out. */
static void field_name(int k, int j, char* out, size_t size) {
  snprintf(out, size, "sensors.%s.%s", kSensors[k].name, kSensors[k].keys[j]);
}

static f3r_status validate_sensor(const f3r_sensor_scene* s, int k, f3r_error* err) {
  char f[96];
  snprintf(f, sizeof f, "sensors.%s.rate", kSensors[k].name);
  if (!(s->rate > 0.0 && s->rate <= F3R_SENSOR_MAX_RATE))
    return f3r_scene_error(err, f, NULL, "%g is out of range (0, %g] Hz", s->rate,
                           F3R_SENSOR_MAX_RATE);
  snprintf(f, sizeof f, "sensors.%s.delay", kSensors[k].name);
  if (s->delay < 0 || s->delay > F3R_SENSOR_MAX_DELAY)
    return f3r_scene_error(err, f, NULL, "%d is out of range 0..%d periods", s->delay,
                           F3R_SENSOR_MAX_DELAY);
  snprintf(f, sizeof f, "sensors.%s.seed", kSensors[k].name);
  if (s->seed < 0)
    return f3r_scene_error(err, f, NULL, "%d is out of range 0..2147483647", s->seed);
  for (int j = 0; j < 4; ++j) {
    if (!kSensors[k].keys[j]) continue;
    const double v = j < 2 ? s->noise[j] : s->resolution[j - 2];
    field_name(k, j, f, sizeof f);
    if (!(v >= 0.0 && isfinite(v)))
      return f3r_scene_error(err, f, NULL, "%g must be finite and at least 0", v);
  }
  return F3R_OK;
}

f3r_status f3r_sensors_scene_validate(const f3r_sensors_scene* sensors, f3r_error* err) {
  const f3r_sensor_scene* all[3] = {&sensors->encoders, &sensors->strain_gauges,
                                    &sensors->accelerometer};
  for (int k = 0; k < 3; ++k) {
    if (!all[k]->enabled) continue;
    const f3r_status st = validate_sensor(all[k], k, err);
    if (st != F3R_OK) return st;
  }
  return F3R_OK;
}

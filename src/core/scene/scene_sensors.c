/* The scene's sensors section: defaults, YAML keys and range checks (docs/scenes.md, sensors).
 *
 *   sensors:
 *     NAME: {rate, delay, seed, enabled, and the kind's noise and resolution keys}
 *
 * NAME and the keys are the kinds' table's (sensor_kinds.c). A sensor named in the file is
 * enabled unless it says enabled: false. */
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

/* The key of noise[0], noise[1], resolution[0], resolution[1] (j) of kind; NULL when it has
 * none. */
static const char* value_key(const f3r_sensor_kind* kind, int j) {
  return j < 2 ? kind->noise_key[j] : kind->resolution_key[j - 2];
}

static double* value_of(f3r_sensor_scene* s, int j) {
  return j < 2 ? &s->noise[j] : &s->resolution[j - 2];
}

static f3r_status read_sensor(loader* L, const yaml_node_t* map, int k) {
  const f3r_sensor_kind* kind = f3r_sensor_kind_at(k);
  char section[64];
  snprintf(section, sizeof section, "sensors.%s", kind->name);
  f3r_status st = f3r_yaml_mapping(L, map, section);
  if (st != F3R_OK) return st;
  f3r_yaml_remember(L, section, map);
  f3r_sensor_scene* s = &L->scene->sensors.kind[k];
  f3r_sensor_scene_defaults(s);
  FOR_EACH_PAIR(L, map, key, value) {
    char name[128];
    snprintf(name, sizeof name, "%s.%s", section, key);
    double* target = NULL;
    for (int j = 0; j < 4; ++j)
      if (value_key(kind, j) && !strcmp(key, value_key(kind, j))) target = value_of(s, j);
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
        if (value_key(kind, j))
          snprintf(allowed + strlen(allowed), sizeof allowed - strlen(allowed), ", %s",
                   value_key(kind, j));
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
    const int k = f3r_sensor_kind_find(key);
    if (k < 0) {
      char name[96], allowed[256];
      snprintf(name, sizeof name, "sensors.%s", key);
      return f3r_yaml_fail(L, value, name, "unknown sensor (allowed: %s)",
                           f3r_sensor_kind_names(allowed, sizeof allowed));
    }
    if ((st = read_sensor(L, value, k)) != F3R_OK) return st;
  }
  return F3R_OK;
}

static f3r_status validate_sensor(const f3r_sensor_scene* s, int k, f3r_error* err) {
  const char* sensor = f3r_sensor_kind_at(k)->name;
  char f[96];
  snprintf(f, sizeof f, "sensors.%s.rate", sensor);
  if (!(s->rate > 0.0 && s->rate <= F3R_SENSOR_MAX_RATE))
    return f3r_scene_error(err, f, NULL, "%g is out of range (0, %g] Hz", s->rate,
                           F3R_SENSOR_MAX_RATE);
  snprintf(f, sizeof f, "sensors.%s.delay", sensor);
  if (s->delay < 0 || s->delay > F3R_SENSOR_MAX_DELAY)
    return f3r_scene_error(err, f, NULL, "%d is out of range 0..%d periods", s->delay,
                           F3R_SENSOR_MAX_DELAY);
  snprintf(f, sizeof f, "sensors.%s.seed", sensor);
  if (s->seed < 0)
    return f3r_scene_error(err, f, NULL, "%d is out of range 0..2147483647", s->seed);
  for (int j = 0; j < 4; ++j) {
    const char* key = value_key(f3r_sensor_kind_at(k), j);
    if (!key) continue;
    const double v = j < 2 ? s->noise[j] : s->resolution[j - 2];
    snprintf(f, sizeof f, "sensors.%s.%s", sensor, key);
    if (!(v >= 0.0 && isfinite(v)))
      return f3r_scene_error(err, f, NULL, "%g must be finite and at least 0", v);
  }
  return F3R_OK;
}

f3r_status f3r_sensors_scene_validate(const f3r_sensors_scene* sensors, f3r_error* err) {
  for (int k = 0; k < F3R_SENSOR_MAX_KINDS; ++k) {
    if (!sensors->kind[k].enabled) continue;
    if (k >= f3r_sensor_kind_count())
      return f3r_scene_error(err, "sensors", NULL, "sensor %d is enabled but there are only %d", k,
                             f3r_sensor_kind_count());
    const f3r_status st = validate_sensor(&sensors->kind[k], k, err);
    if (st != F3R_OK) return st;
  }
  return F3R_OK;
}

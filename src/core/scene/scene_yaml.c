/* Scene YAML (libyaml document API) into f3r_scene. Unknown keys are errors; every error reads
 * "path:line: field: what is wrong". Range checks are f3r_scene_validate's, which names the field
 * at fault in err->field; the loader remembers the line of every field it read (no cap: a
 * 1024-point table is 2048 of them) so that those messages carry it too. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "flex3rpr/scene.h"
#include "scene_overrides.h"
#include "scene_yaml_reader.h"

static f3r_status read_link(loader* L, const yaml_node_t* map, int i) {
  char section[32];
  snprintf(section, sizeof section, "links[%d]", i);
  f3r_status st = f3r_yaml_mapping(L, map, section);
  if (st != F3R_OK) return st;
  f3r_yaml_remember(L, section, map);
  f3r_link_scene* link = &L->scene->links[i];
  FOR_EACH_PAIR(L, map, key, value) {
    char name[96];
    snprintf(name, sizeof name, "%s.%s", section, key);
    if (!strcmp(key, "model")) {
      const char* s = f3r_yaml_scalar(value);
      char allowed[64];
      if (f3r_link_model_from_name(s, &link->model) != 0)
        return f3r_yaml_fail(L, value, name, "'%s' is not one of %s", s ? s : "?",
                             f3r_link_model_names(allowed, sizeof allowed));
      f3r_yaml_remember(L, name, value);
    } else if (!strcmp(key, "modes")) {
      const char* v = f3r_yaml_scalar(value);
      if (v && !strcmp(v, "auto")) {
        link->modes = F3R_MODES_AUTO;
        f3r_yaml_remember(L, name, value);
      } else if ((st = f3r_yaml_int(L, value, name, &link->modes)) != F3R_OK) {
        return f3r_yaml_fail(L, value, name, "expected 1..%d or auto", F3R_MAX_MODES);
      } else {
        L->scene->explicit_settings |= F3R_EXPLICIT_MODES << i;
      }
    } else if (!strcmp(key, "auto_tolerance")) {
      if ((st = f3r_yaml_number(L, value, name, &link->auto_tolerance)) != F3R_OK) return st;
    } else if (!strcmp(key, "static_correction")) {
      if ((st = f3r_yaml_bool(L, value, name, &link->static_correction)) != F3R_OK) return st;
      L->scene->explicit_settings |= F3R_EXPLICIT_STATIC_CORRECTION << i;
      f3r_yaml_remember(L, name, value);
    } else if (!strcmp(key, "shape_mix")) {
      const char* v = f3r_yaml_scalar(value);
      if (v && !strcmp(v, "fit")) {
        link->shape_mix_kind = F3R_SHAPE_MIX_FIT;
      } else if (f3r_yaml_number(L, value, name, &link->shape_mix) != F3R_OK) {
        return f3r_yaml_fail(L, value, name, "expected a number in -%g..%g or fit",
                             F3R_SHAPE_MIX_LIMIT, F3R_SHAPE_MIX_LIMIT);
      } else {
        link->shape_mix_kind = F3R_SHAPE_MIXED;
      }
      f3r_yaml_remember(L, name, value);
    } else if (!strcmp(key, "damping_ratio")) {
      if ((st = f3r_yaml_number(L, value, name, &link->damping_ratio)) != F3R_OK) return st;
    } else if (!strcmp(key, "initial_deflection") || !strcmp(key, "initial_rate")) {
      double* target = key[8] == 'd' ? link->eta0 : link->eta_rate0;
      if (value->type != YAML_SEQUENCE_NODE)
        return f3r_yaml_fail(L, value, name, "expected a list");
      const int len = (int)(value->data.sequence.items.top - value->data.sequence.items.start);
      if (len > F3R_MAX_MODES)
        return f3r_yaml_fail(L, value, name, "has %d values, at most %d allowed", len,
                             F3R_MAX_MODES);
      if ((st = f3r_yaml_vector(L, value, name, target, len)) != F3R_OK) return st;
    } else {
      return f3r_yaml_fail(L, value, name,
                           "unknown key (allowed: model, modes, static_correction, shape_mix, "
                           "auto_tolerance, damping_ratio, initial_deflection, initial_rate)");
    }
  }
  return F3R_OK;
}

static f3r_status read_links(loader* L, const yaml_node_t* n) {
  if (n->type == YAML_MAPPING_NODE) { /* one mapping applies to all three links */
    for (int i = 0; i < 3; ++i) {
      f3r_status st = read_link(L, n, i);
      if (st != F3R_OK) return st;
    }
    return F3R_OK;
  }
  if (n->type != YAML_SEQUENCE_NODE)
    return f3r_yaml_fail(L, n, "links", "expected a list of 3 links or one mapping for all");
  const int len = (int)(n->data.sequence.items.top - n->data.sequence.items.start);
  if (len != 3) return f3r_yaml_fail(L, n, "links", "has %d entries, expected 3", len);
  for (int i = 0; i < 3; ++i) {
    f3r_status st =
        read_link(L, yaml_document_get_node(&L->doc, n->data.sequence.items.start[i]), i);
    if (st != F3R_OK) return st;
  }
  return F3R_OK;
}

/* A mapping {key: number} into the fields named in `fields`; every key must be known. */
static f3r_status read_shape(loader* L, const yaml_node_t* map, const char* name,
                             const number_field* fields, int count) {
  return f3r_yaml_numbers(L, map, name, fields, count);
}

/* A table's list of numbers, 2..F3R_MAX_TABLE of them; *len is its length. */
static f3r_status table_list(loader* L, const yaml_node_t* value, const char* field, int* len) {
  if (value->type != YAML_SEQUENCE_NODE)
    return f3r_yaml_fail(L, value, field, "expected a list of numbers");
  *len = (int)(value->data.sequence.items.top - value->data.sequence.items.start);
  if (*len < 2 || *len > F3R_MAX_TABLE)
    return f3r_yaml_fail(L, value, field, "has %d values, allowed 2..%d", *len, F3R_MAX_TABLE);
  return F3R_OK;
}

/* The lists are read straight into the table's block of exactly their size, which the input
 * then owns (f3r_scene_free). */
static f3r_status read_table(loader* L, const yaml_node_t* map, const char* name, f3r_input* in) {
  f3r_status st = f3r_yaml_mapping(L, map, name);
  if (st != F3R_OK) return st;
  const yaml_node_t *times = NULL, *values = NULL;
  char time_field[128] = "", value_field[128] = "";
  int n_time = -1, n_value = -1;
  FOR_EACH_PAIR(L, map, key, value) {
    char field[128];
    snprintf(field, sizeof field, "%s.%s", name, key);
    if (!strcmp(key, "interpolation")) {
      const char* v = f3r_yaml_scalar(value);
      if (v && !strcmp(v, "linear"))
        in->table_hold = 0;
      else if (v && !strcmp(v, "hold"))
        in->table_hold = 1;
      else
        return f3r_yaml_fail(L, value, field, "'%s' is not allowed (linear or hold)", v ? v : "?");
      continue;
    }
    const int is_time = !strcmp(key, "time");
    if (!is_time && strcmp(key, "value"))
      return f3r_yaml_fail(L, value, field, "unknown key (allowed: time, value, interpolation)");
    if ((st = table_list(L, value, field, is_time ? &n_time : &n_value)) != F3R_OK) return st;
    *(is_time ? &times : &values) = value;
    snprintf(is_time ? time_field : value_field, 128, "%s", field);
  }
  if (n_time < 0 || n_value < 0)
    return f3r_yaml_fail(L, map, name, "needs both time and value lists");
  if (n_time != n_value)
    return f3r_yaml_fail(L, map, name, "time has %d values but value has %d", n_time, n_value);
  double* block = malloc(2 * (size_t)n_time * sizeof(double));
  if (!block) return f3r_error_set(L->err, F3R_ERR_MEMORY, "%s: out of memory", L->path);
  free(in->table_time); /* a table read before, under an override */
  in->table_time = block;
  in->table_value = block + n_time;
  in->table_size = n_time;
  if ((st = f3r_yaml_vector(L, times, time_field, in->table_time, n_time)) != F3R_OK) return st;
  if ((st = f3r_yaml_vector(L, values, value_field, in->table_value, n_value)) != F3R_OK) return st;
  f3r_yaml_remember(L, name, map);
  return F3R_OK;
}

static f3r_status read_input(loader* L, const yaml_node_t* map, const char* name, f3r_input* in) {
  f3r_status st = f3r_yaml_mapping(L, map, name);
  if (st != F3R_OK) return st;
  f3r_yaml_remember(L, name, map);
  /* A shaped input is a one-key mapping naming its shape. */
  if (map->data.mapping.pairs.top - map->data.mapping.pairs.start == 1) {
    const yaml_node_t* key_node =
        yaml_document_get_node(&L->doc, map->data.mapping.pairs.start->key);
    const yaml_node_t* value =
        yaml_document_get_node(&L->doc, map->data.mapping.pairs.start->value);
    const char* key = f3r_yaml_scalar(key_node) ? f3r_yaml_scalar(key_node) : "";
    char field[128];
    snprintf(field, sizeof field, "%s.%s", name, key);
    if (!strcmp(key, "step")) {
      in->kind = F3R_INPUT_STEP;
      const number_field f[] = {F3R_NUMBER("time", &in->t0), F3R_NUMBER("before", &in->before),
                                F3R_NUMBER("after", &in->after)};
      return read_shape(L, value, field, f, 3);
    }
    if (!strcmp(key, "ramp")) {
      in->kind = F3R_INPUT_RAMP;
      const number_field f[] = {F3R_NUMBER("start", &in->t0), F3R_NUMBER("end", &in->t1),
                                F3R_NUMBER("from", &in->before), F3R_NUMBER("to", &in->after)};
      return read_shape(L, value, field, f, 4);
    }
    if (!strcmp(key, "chirp")) {
      in->kind = F3R_INPUT_CHIRP;
      const number_field f[] = {
          F3R_NUMBER("offset", &in->offset),      F3R_NUMBER("amplitude", &in->amplitude),
          F3R_NUMBER("start_frequency", &in->f0), F3R_NUMBER("end_frequency", &in->f1),
          F3R_NUMBER("start", &in->t0),           F3R_NUMBER("end", &in->t1)};
      return read_shape(L, value, field, f, 6);
    }
    if (!strcmp(key, "table")) {
      in->kind = F3R_INPUT_TABLE;
      return read_table(L, value, field, in);
    }
  }
  double frequency = NAN;
  in->kind = F3R_INPUT_CONSTANT;
  FOR_EACH_PAIR(L, map, key, value) {
    char field[128];
    snprintf(field, sizeof field, "%s.%s", name, key);
    double* target = !strcmp(key, "offset")      ? &in->offset
                     : !strcmp(key, "amplitude") ? &in->amplitude
                     : !strcmp(key, "omega")     ? &in->omega
                     : !strcmp(key, "phase")     ? &in->phase
                     : !strcmp(key, "frequency") ? &frequency
                                                 : NULL;
    if (!target)
      return f3r_yaml_fail(
          L, value, field,
          "unknown key (allowed: offset, amplitude, frequency, omega, phase; or one of "
          "step, ramp, chirp, table)");
    if ((st = f3r_yaml_number(L, value, field, target)) != F3R_OK) return st;
    if (target != &in->offset) in->kind = F3R_INPUT_HARMONIC;
  }
  if (!isnan(frequency)) {
    if (in->omega != 0.0)
      return f3r_yaml_fail(L, map, name, "give frequency (Hz) or omega (rad/s), not both");
    if (frequency < 0.0)
      return f3r_yaml_fail(L, map, name, "frequency: %g Hz must not be negative", frequency);
    in->omega = 2.0 * M_PI * frequency;
  }
  return F3R_OK;
}

static f3r_status read_inputs(loader* L, const yaml_node_t* map) {
  f3r_status st = f3r_yaml_mapping(L, map, "inputs");
  if (st != F3R_OK) return st;
  FOR_EACH_PAIR(L, map, key, value) {
    char name[96];
    snprintf(name, sizeof name, "inputs.%s", key);
    int index = -1;
    for (int k = 0; k < F3R_RIGID_FORCES; ++k)
      if (!strcmp(key, f3r_input_name(k))) index = k;
    if (index < 0)
      return f3r_yaml_fail(L, value, name,
                           "unknown input (allowed: rho_1..3, theta_1..3, platform_force_x, "
                           "platform_force_y, platform_torque)");
    if ((st = read_input(L, value, name, &L->scene->inputs[index])) != F3R_OK) return st;
  }
  return F3R_OK;
}

/* A solver setting named from one of the core's enum tables (names.c): parsed says whether the
 * table knew the name; allowed lists the names. */
static f3r_status named_setting(loader* L, const yaml_node_t* value, const char* field, int parsed,
                                const char* allowed, unsigned explicit_bit) {
  if (!parsed) {
    const char* v = f3r_yaml_scalar(value);
    return f3r_yaml_fail(L, value, field, "'%s' is not one of %s", v ? v : "?", allowed);
  }
  L->scene->explicit_settings |= explicit_bit;
  f3r_yaml_remember(L, field, value);
  return F3R_OK;
}

static f3r_status read_solver(loader* L, const yaml_node_t* map) {
  f3r_status st = f3r_yaml_mapping(L, map, "solver");
  if (st != F3R_OK) return st;
  f3r_scene* s = L->scene;
  FOR_EACH_PAIR(L, map, key, value) {
    char name[96];
    snprintf(name, sizeof name, "solver.%s", key);
    const char* v = f3r_yaml_scalar(value);
    char allowed[64];
    if (!strcmp(key, "formulation")) {
      st = named_setting(L, value, name, f3r_formulation_from_name(v, &s->formulation) == 0,
                         f3r_formulation_names(allowed, sizeof allowed), F3R_EXPLICIT_FORMULATION);
    } else if (!strcmp(key, "integrator")) {
      st = named_setting(L, value, name, f3r_integrator_from_name(v, &s->integrator) == 0,
                         f3r_integrator_names(allowed, sizeof allowed), F3R_EXPLICIT_INTEGRATOR);
    } else if (!strcmp(key, "table")) {
      if (!v || !*v || strlen(v) >= sizeof s->table)
        return f3r_yaml_fail(L, value, name, "needs a Butcher table's name (at most %d characters)",
                             (int)sizeof s->table - 1);
      snprintf(s->table, sizeof s->table, "%s", v);
      s->explicit_settings |= F3R_EXPLICIT_TABLE;
      f3r_yaml_remember(L, name, value);
    } else if (!strcmp(key, "rtol")) {
      st = f3r_yaml_number(L, value, name, &s->rtol);
      s->explicit_settings |= F3R_EXPLICIT_RTOL;
    } else if (!strcmp(key, "atol")) {
      st = f3r_yaml_number(L, value, name, &s->atol);
      s->explicit_settings |= F3R_EXPLICIT_ATOL;
    } else if (!strcmp(key, "max_step")) {
      st = f3r_yaml_number(L, value, name, &s->max_step);
    } else if (!strcmp(key, "max_order")) {
      double order = 0.0;
      st = f3r_yaml_number(L, value, name, &order);
      if (st == F3R_OK && (order != floor(order) || order < 1 || order > 5))
        return f3r_yaml_fail(L, value, name, "%g is out of range 1..5 (an integer)", order);
      s->max_order = (int)order;
    } else {
      return f3r_yaml_fail(
          L, value, name,
          "unknown key (allowed: formulation, integrator, table, rtol, atol, max_step, max_order)");
    }
    if (st != F3R_OK) return st;
  }
  return F3R_OK;
}

static f3r_status read_joint_friction(loader* L, const yaml_node_t* map, const char* name) {
  f3r_scene* s = L->scene;
  f3r_status st = f3r_yaml_mapping(L, map, name);
  if (st != F3R_OK) return st;
  FOR_EACH_PAIR(L, map, fkey, fvalue) {
    char field[128];
    snprintf(field, sizeof field, "%s.%s", name, fkey);
    double* target = !strcmp(fkey, "prismatic")  ? s->friction_prismatic
                     : !strcmp(fkey, "revolute") ? s->friction_revolute
                                                 : NULL;
    if (!target)
      return f3r_yaml_fail(L, fvalue, field, "unknown key (allowed: prismatic, revolute)");
    if ((st = f3r_yaml_vector(L, fvalue, field, target, 3)) != F3R_OK) return st;
  }
  return F3R_OK;
}

static f3r_status read_effects(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  f3r_status st = f3r_yaml_mapping(L, map, "effects");
  if (st != F3R_OK) return st;
  FOR_EACH_PAIR(L, map, ekey, evalue) {
    char name[96];
    snprintf(name, sizeof name, "effects.%s", ekey);
    if (!strcmp(ekey, "exact_kinematics")) {
      st = f3r_yaml_bool(L, evalue, name, &s->exact_kinematics);
      s->explicit_settings |= F3R_EXPLICIT_EXACT_KINEMATICS;
    } else if (!strcmp(ekey, "gravity")) {
      st = f3r_yaml_vector(L, evalue, name, s->gravity, 3);
    } else if (!strcmp(ekey, "payload")) {
      const number_field f[] = {F3R_NUMBER("mass", &s->payload_mass),
                                F3R_NUMBER("inertia", &s->payload_inertia)};
      st = f3r_yaml_numbers(L, evalue, name, f, 2);
    } else if (!strcmp(ekey, "end_stops")) {
      const number_field f[] = {F3R_NUMBER("min", &s->stroke_min),
                                F3R_NUMBER("max", &s->stroke_max),
                                F3R_NUMBER("restitution", &s->restitution)};
      s->end_stops = 1;
      st = f3r_yaml_numbers(L, evalue, name, f, 3);
    } else if (!strcmp(ekey, "actuator_lag")) {
      const number_field f[] = {F3R_NUMBER("time_constant", &s->actuator_lag)};
      st = f3r_yaml_numbers(L, evalue, name, f, 1);
    } else if (!strcmp(ekey, "joint_friction")) {
      st = read_joint_friction(L, evalue, name);
    } else {
      return f3r_yaml_fail(
          L, evalue, name,
          "unknown effect (allowed: exact_kinematics, gravity, payload, joint_friction, "
          "actuator_lag, end_stops)");
    }
    if (st != F3R_OK) return st;
  }
  return F3R_OK;
}

static f3r_status read_initial(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  const number_field f[] = {F3R_VECTOR("platform_pose", s->platform_pose0, 3),
                            F3R_VECTOR("platform_velocity", s->platform_velocity0, 3)};
  return f3r_yaml_numbers(L, map, "initial", f, 2);
}

static f3r_status read_limits(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  const number_field f[] = {F3R_NUMBER("force", &s->limit_force),
                            F3R_NUMBER("torque", &s->limit_torque),
                            F3R_NUMBER("modal_force", &s->limit_modal_force)};
  return f3r_yaml_numbers(L, map, "limits", f, 3);
}

static f3r_status read_run(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  const number_field f[] = {F3R_NUMBER("duration", &s->duration),
                            F3R_NUMBER("output_step", &s->output_step),
                            F3R_INTEGER("beam_points", &s->beam_points)};
  return f3r_yaml_numbers(L, map, "run", f, 3);
}

static f3r_status read_geometry(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  const number_field f[] = {
      F3R_NUMBER("base_side", &s->base_side), F3R_NUMBER("platform_side", &s->platform_side),
      F3R_NUMBER("stroke_min", &s->stroke_min), F3R_NUMBER("stroke_max", &s->stroke_max)};
  return f3r_yaml_numbers(L, map, "geometry", f, 4);
}

static f3r_status read_platform(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  const number_field f[] = {F3R_NUMBER("mass", &s->platform_mass),
                            F3R_NUMBER("inertia", &s->platform_inertia)};
  return f3r_yaml_numbers(L, map, "platform", f, 2);
}

static f3r_status read_link_material(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  const number_field f[] = {F3R_NUMBER("length", &s->link_length),
                            F3R_NUMBER("diameter", &s->link_diameter),
                            F3R_NUMBER("density", &s->link_density),
                            F3R_NUMBER("youngs_modulus", &s->link_youngs_modulus)};
  return f3r_yaml_numbers(L, map, "link", f, 4);
}

static f3r_status read_cylinder(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  const number_field f[] = {F3R_NUMBER("length", &s->cylinder_length),
                            F3R_NUMBER("inner_diameter", &s->cylinder_inner_diameter),
                            F3R_NUMBER("outer_diameter", &s->cylinder_outer_diameter),
                            F3R_NUMBER("density", &s->cylinder_density)};
  return f3r_yaml_numbers(L, map, "cylinder", f, 4);
}

static f3r_status read_accuracy(loader* L, const yaml_node_t* map) {
  f3r_scene* s = L->scene;
  f3r_status st = f3r_yaml_mapping(L, map, "accuracy");
  if (st != F3R_OK) return st;
  FOR_EACH_PAIR(L, map, key, value) {
    if (st != F3R_OK) break;
    char name[96];
    snprintf(name, sizeof name, "accuracy.%s", key);
    if (!strcmp(key, "end_effector"))
      st = f3r_yaml_number(L, value, name, &s->accuracy);
    else if (!strcmp(key, "verify"))
      st = f3r_yaml_bool(L, value, name, &s->accuracy_verify);
    else if (!strcmp(key, "escalations"))
      st = f3r_yaml_int(L, value, name, &s->accuracy_escalations);
    else if (!strcmp(key, "excitation"))
      st = f3r_yaml_number(L, value, name, &s->accuracy_excitation);
    else
      st = f3r_yaml_fail(L, value, name,
                         "unknown key (allowed: end_effector, verify, escalations, excitation)");
  }
  return st;
}

/* The scene file's sections, in the order the documentation lists them. */
static const struct {
  const char* name;
  f3r_status (*read)(loader* L, const yaml_node_t* node);
} sections[] = {
    {"geometry", read_geometry},       {"platform", read_platform}, {"link", read_link_material},
    {"cylinder", read_cylinder},       {"links", read_links},       {"effects", read_effects},
    {"initial", read_initial},         {"inputs", read_inputs},     {"solver", read_solver},
    {"accuracy", read_accuracy},       {"limits", read_limits},     {"run", read_run},
    {"sensors", f3r_yaml_read_sensors}};

static f3r_status read_root(loader* L, const yaml_node_t* root) {
  f3r_status st = f3r_yaml_mapping(L, root, "scene");
  if (st != F3R_OK) return st;
  const int count = (int)(sizeof sections / sizeof sections[0]);
  FOR_EACH_PAIR(L, root, key, value) {
    int k = 0;
    while (k < count && strcmp(key, sections[k].name)) ++k;
    if (k == count) {
      char allowed[160] = "";
      for (int j = 0; j < count; ++j)
        snprintf(allowed + strlen(allowed), sizeof allowed - strlen(allowed), "%s%s", j ? ", " : "",
                 sections[j].name);
      return f3r_yaml_fail(L, value, key, "unknown section (allowed: %s)", allowed);
    }
    if ((st = sections[k].read(L, value)) != F3R_OK) return st;
  }
  return F3R_OK;
}

/* Prefixes a validation message with the file and the line of the field it names. A field the
 * file does not hold (a default that another value puts out of range) gets the line of its
 * section, or 0 when the file has no part of it. */
static f3r_status locate_validation_error(loader* L, f3r_error* err) {
  const field_location* at = f3r_yaml_location(L, err->field);
  char message[sizeof err->message], field[sizeof err->field], place[320];
  f3r_yaml_where(L, at ? at->line : 0, at ? at->override : 0, place, sizeof place);
  snprintf(message, sizeof message, "%s: %s", place, err->message);
  snprintf(field, sizeof field, "%s", err->field);
  f3r_error_set(err, err->code, "%s", message);
  snprintf(err->field, sizeof err->field, "%s", field);
  return err->code;
}

f3r_status f3r_scene_load(const char* path, f3r_scene* scene, f3r_error* err) {
  return f3r_scene_load_accuracy(path, 0.0, scene, err);
}

f3r_status f3r_scene_load_accuracy(const char* path, double accuracy, f3r_scene* scene,
                                   f3r_error* err) {
  const f3r_scene_options options = {.accuracy = accuracy};
  return f3r_scene_load_with(path, &options, scene, err);
}

f3r_status f3r_scene_load_with(const char* path, const f3r_scene_options* options, f3r_scene* scene,
                               f3r_error* err) {
  if (!path || !scene || !options || (options->override_count > 0 && !options->overrides))
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_scene_load: NULL argument");
  const double accuracy = options->accuracy;
  FILE* file = fopen(path, "rb");
  if (!file) return f3r_error_set(err, F3R_ERR_SCENE, "%s: cannot open: %s", path, strerror(errno));
  loader* L = calloc(1, sizeof *L);
  if (!L) {
    fclose(file);
    return f3r_error_set(err, F3R_ERR_MEMORY, "%s: out of memory", path);
  }
  L->path = path;
  L->err = err;
  L->overrides = options->overrides;
  L->override_count = options->override_count > 0 ? options->override_count : 0;
  if (L->override_count) {
    L->first_node = calloc((size_t)L->override_count, sizeof *L->first_node);
    L->last_node = calloc((size_t)L->override_count, sizeof *L->last_node);
    if (!L->first_node || !L->last_node) {
      free(L->first_node), free(L->last_node), free(L);
      fclose(file);
      return f3r_error_set(err, F3R_ERR_MEMORY, "%s: out of memory", path);
    }
  }
  f3r_scene parsed = f3r_default_scene();
  L->scene = &parsed;
  yaml_parser_t parser;
  yaml_parser_initialize(&parser);
  yaml_parser_set_input_file(&parser, file);
  f3r_status st;
  if (!yaml_parser_load(&parser, &L->doc)) {
    st = f3r_error_set(err, F3R_ERR_SCENE, "%s:%d: YAML syntax: %s", path,
                       (int)parser.problem_mark.line + 1, parser.problem ? parser.problem : "?");
    yaml_parser_delete(&parser);
    fclose(file);
    free(L->first_node), free(L->last_node), free(L);
    return st;
  }
  st = yaml_document_get_root_node(&L->doc)
           ? F3R_OK
           : f3r_error_set(err, F3R_ERR_SCENE, "%s:1: the file holds no scene", path);
  for (int k = 0; st == F3R_OK && k < L->override_count; ++k)
    st = f3r_scene_apply_override(&L->doc, path, L->overrides[k], &L->first_node[k],
                                  &L->last_node[k], err);
  if (st == F3R_OK) st = read_root(L, yaml_document_get_root_node(&L->doc));
  if (st == F3R_OK && L->out_of_memory)
    st = f3r_error_set(err, F3R_ERR_MEMORY, "%s: out of memory", path);
  if (st == F3R_OK && accuracy > 0.0) parsed.accuracy = accuracy;
  if (st == F3R_OK) {
    st = f3r_scene_validate(&parsed, err);
    if (st != F3R_OK) st = locate_validation_error(L, err);
  }
  if (st == F3R_OK)
    *scene = parsed; /* the tables go with it */
  else
    f3r_scene_free(&parsed);
  yaml_document_delete(&L->doc);
  yaml_parser_delete(&parser);
  fclose(file);
  free(L->fields);
  free(L->first_node), free(L->last_node), free(L);
  return st;
}

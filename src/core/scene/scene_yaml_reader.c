/* The scene loader's typed readers (scene_yaml_reader.h). */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_yaml_reader.h"

static int f3r_yaml_line(const yaml_node_t* node) { return (int)node->start_mark.line + 1; }

/* 1 + the override that added `node`, 0 if the file holds it. */
static int override_of(const loader* L, const yaml_node_t* node) {
  if (!node) return 0;
  const int id = (int)(node - L->doc.nodes.start) + 1;
  for (int k = 0; k < L->override_count; ++k)
    if (id >= L->first_node[k] && id <= L->last_node[k]) return k + 1;
  return 0;
}

/* Where a message points: "path:line" in the file, or "--set FIELD=VALUE" for an override. */
void f3r_yaml_where(const loader* L, int line, int override, char* out, size_t size) {
  if (override)
    snprintf(out, size, "--set %s", L->overrides[override - 1]);
  else
    snprintf(out, size, "%s:%d", L->path, line);
}

f3r_status f3r_yaml_fail(loader* L, const yaml_node_t* node, const char* field, const char* fmt,
                         ...) {
  char what[384], at[320];
  va_list args;
  va_start(args, fmt);
  vsnprintf(what, sizeof what, fmt, args);
  va_end(args);
  f3r_yaml_where(L, node ? f3r_yaml_line(node) : 0, override_of(L, node), at, sizeof at);
  return f3r_error_set(L->err, F3R_ERR_SCENE, "%s: %s: %s", at, field, what);
}

void f3r_yaml_remember(loader* L, const char* field, const yaml_node_t* node) {
  if (L->n_fields == L->capacity) {
    const int capacity = L->capacity ? 2 * L->capacity : 64;
    field_location* grown = realloc(L->fields, (size_t)capacity * sizeof *grown);
    if (!grown) {
      L->out_of_memory = 1;
      return;
    }
    L->fields = grown;
    L->capacity = capacity;
  }
  field_location* f = &L->fields[L->n_fields++];
  snprintf(f->name, sizeof f->name, "%s", field);
  f->line = f3r_yaml_line(node);
  f->override = override_of(L, node);
}

/* The location of `field`: its own, else that of the nearest enclosing field that was read
 * ("links[1]" for "links[1].modes" when the modes were left to their default); NULL if none. */
const field_location* f3r_yaml_location(const loader* L, const char* field) {
  const field_location* found = NULL;
  size_t best = 0;
  for (int k = L->n_fields - 1; k >= 0; --k) {
    const char* name = L->fields[k].name;
    const size_t n = strlen(name);
    if (!strcmp(name, field)) return &L->fields[k];
    if (n > best && !strncmp(field, name, n) && (field[n] == '.' || field[n] == '[')) {
      best = n;
      found = &L->fields[k];
    }
  }
  return found;
}

const char* f3r_yaml_scalar(const yaml_node_t* n) {
  return n->type == YAML_SCALAR_NODE ? (const char*)n->data.scalar.value : NULL;
}

f3r_status f3r_yaml_number(loader* L, const yaml_node_t* n, const char* field, double* out) {
  const char* s = f3r_yaml_scalar(n);
  if (!s) return f3r_yaml_fail(L, n, field, "expected a number");
  char* end = NULL;
  errno = 0;
  const double v = strtod(s, &end);
  if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v))
    return f3r_yaml_fail(L, n, field, "'%s' is not a finite number", s);
  *out = v;
  f3r_yaml_remember(L, field, n);
  return F3R_OK;
}

f3r_status f3r_yaml_int(loader* L, const yaml_node_t* n, const char* field, int* out) {
  double v = 0.0;
  f3r_status st = f3r_yaml_number(L, n, field, &v);
  if (st != F3R_OK) return st;
  if (v != floor(v) || fabs(v) > 1e6)
    return f3r_yaml_fail(L, n, field, "%g is not a whole number", v);
  *out = (int)v;
  return F3R_OK;
}

f3r_status f3r_yaml_bool(loader* L, const yaml_node_t* n, const char* field, int* out) {
  const char* s = f3r_yaml_scalar(n);
  if (s && (!strcmp(s, "true") || !strcmp(s, "on") || !strcmp(s, "yes")))
    *out = 1;
  else if (s && (!strcmp(s, "false") || !strcmp(s, "off") || !strcmp(s, "no")))
    *out = 0;
  else
    return f3r_yaml_fail(L, n, field, "expected true or false");
  f3r_yaml_remember(L, field, n);
  return F3R_OK;
}

f3r_status f3r_yaml_vector(loader* L, const yaml_node_t* n, const char* field, double* out,
                           int count) {
  if (n->type != YAML_SEQUENCE_NODE)
    return f3r_yaml_fail(L, n, field, "expected a list of %d numbers", count);
  const int len = (int)(n->data.sequence.items.top - n->data.sequence.items.start);
  if (len != count) return f3r_yaml_fail(L, n, field, "has %d values, expected %d", len, count);
  for (int k = 0; k < len; ++k) {
    char name[96];
    snprintf(name, sizeof name, "%s[%d]", field, k);
    const yaml_node_t* item = yaml_document_get_node(&L->doc, n->data.sequence.items.start[k]);
    f3r_status st = f3r_yaml_number(L, item, name, &out[k]);
    if (st != F3R_OK) return st;
  }
  f3r_yaml_remember(L, field, n);
  return F3R_OK;
}

f3r_status f3r_yaml_mapping(loader* L, const yaml_node_t* n, const char* field) {
  return n->type == YAML_MAPPING_NODE ? F3R_OK : f3r_yaml_fail(L, n, field, "expected a mapping");
}

/* Reads a mapping whose keys are all numbers from `fields`. */
f3r_status f3r_yaml_numbers(loader* L, const yaml_node_t* map, const char* section,
                            const number_field* fields, int count) {
  f3r_status st = f3r_yaml_mapping(L, map, section);
  if (st != F3R_OK) return st;
  FOR_EACH_PAIR(L, map, key, value) {
    char name[96];
    snprintf(name, sizeof name, "%s.%s", section, key);
    int found = 0;
    for (int k = 0; k < count && !found; ++k)
      if (!strcmp(key, fields[k].key)) {
        found = 1;
        const number_field* f = &fields[k];
        st = f->int_target  ? f3r_yaml_int(L, value, name, f->int_target)
             : f->count > 1 ? f3r_yaml_vector(L, value, name, f->target, f->count)
                            : f3r_yaml_number(L, value, name, f->target);
        if (st != F3R_OK) return st;
      }
    if (!found) {
      char allowed[256] = "";
      for (int k = 0; k < count; ++k) {
        strncat(allowed, fields[k].key, sizeof allowed - strlen(allowed) - 1);
        if (k + 1 < count) strncat(allowed, ", ", sizeof allowed - strlen(allowed) - 1);
      }
      return f3r_yaml_fail(L, value, name, "unknown key (allowed: %s)", allowed);
    }
  }
  return F3R_OK;
}

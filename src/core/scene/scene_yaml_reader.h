/* The scene loader's typed readers (scene_yaml.c reads the sections with them): each reads one
 * YAML node into a field, remembers where the field came from (so that a range error found later
 * by f3r_scene_validate can name the line), and fails with "path:line: field: what is wrong".
 * Internal to the core. */
#ifndef F3R_SCENE_YAML_READER_H
#define F3R_SCENE_YAML_READER_H

#include <stddef.h>
#include <yaml.h>

#include "flex3rpr/scene.h"

typedef struct {
  char name
      [128]; /* the field's path, as f3r_scene_validate names it: "inputs.rho_1.table.time[3]" */
  int line;
  int override; /* 1 + the override that set it; 0: the file */
} field_location;

typedef struct {
  const char* path;
  yaml_document_t doc;
  f3r_scene* scene;
  f3r_error* err;
  field_location* fields; /* every field read, in reading order; grown by doubling */
  int n_fields, capacity;
  int out_of_memory; /* a location could not be stored: reported after the read */
  /* Overrides ("--set links[0].modes=4"): override k added the document's nodes
   * first_node[k] .. last_node[k] (ids); a message about one of them names the override. */
  const char* const* overrides;
  int override_count;
  int* first_node;
  int* last_node;
} loader;

/* One key of a section: a number into target (count 0 or 1), a vector of count numbers into
 * target[0..count), or an integer into int_target when that is set. */
typedef struct {
  const char* key;
  double* target;
  int count;
  int* int_target;
} number_field;
#define F3R_NUMBER(key, target) \
  { key, target, 1, NULL }
#define F3R_VECTOR(key, target, count) \
  { key, target, count, NULL }
#define F3R_INTEGER(key, target) \
  { key, NULL, 0, target }

/* Iterates the pairs of a mapping node; KEY is the key string, VALUE the value node. */
#define FOR_EACH_PAIR(L, map, KEY, VALUE)                                                    \
  for (yaml_node_pair_t* pair_ = (map)->data.mapping.pairs.start;                            \
       pair_ < (map)->data.mapping.pairs.top; ++pair_)                                       \
    for (int once_ = 1; once_; once_ = 0)                                                    \
      for (const yaml_node_t *key_node_ = yaml_document_get_node(&(L)->doc, pair_->key),     \
                             *VALUE = yaml_document_get_node(&(L)->doc, pair_->value);       \
           once_; once_ = 0)                                                                 \
        for (const char* KEY = f3r_yaml_scalar(key_node_) ? f3r_yaml_scalar(key_node_) : ""; \
             once_; once_ = 0)

/* Where a message points: "path:line" in the file, or "--set FIELD=VALUE" for an override. */
void f3r_yaml_where(const loader* L, int line, int override, char* out, size_t size);
f3r_status f3r_yaml_fail(loader* L, const yaml_node_t* node, const char* field, const char* fmt,
                         ...) __attribute__((format(printf, 4, 5)));
/* Remembers that `field` was read from `node`. */
void f3r_yaml_remember(loader* L, const char* field, const yaml_node_t* node);
/* The location of `field`: its own, else that of the nearest enclosing field that was read
 * ("links[1]" for "links[1].modes" when the modes were left to their default); NULL if none. */
const field_location* f3r_yaml_location(const loader* L, const char* field);
/* The text of a scalar node, NULL for any other node. */
const char* f3r_yaml_scalar(const yaml_node_t* n);
f3r_status f3r_yaml_number(loader* L, const yaml_node_t* n, const char* field, double* out);
f3r_status f3r_yaml_int(loader* L, const yaml_node_t* n, const char* field, int* out);
f3r_status f3r_yaml_bool(loader* L, const yaml_node_t* n, const char* field, int* out);
f3r_status f3r_yaml_vector(loader* L, const yaml_node_t* n, const char* field, double* out,
                           int count);
f3r_status f3r_yaml_mapping(loader* L, const yaml_node_t* n, const char* field);
/* Reads a mapping whose keys are all from `fields` (numbers, vectors, integers). */
f3r_status f3r_yaml_numbers(loader* L, const yaml_node_t* map, const char* section,
                            const number_field* fields, int count);

/* The sensors section (scene_sensors.c). */
f3r_status f3r_yaml_read_sensors(loader* L, const yaml_node_t* map);

#endif

/* Scene overrides ("--set links[0].modes=4", scene_overrides.h): each edits the parsed YAML
 * document before the loader reads it, so that an override passes the file's own checks. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_overrides.h"

typedef struct {
  yaml_document_t* doc;
  const char* path; /* the scene file, for messages */
  f3r_error* err;
  int first_node; /* the first node id the override added, 0: none yet */
} overriding;

static const char* scalar(const yaml_node_t* n) {
  return n->type == YAML_SCALAR_NODE ? (const char*)n->data.scalar.value : NULL;
}

/* Copies node `id` of `from`, with everything under it, into `to` (which may be `from`), keeping
 * the marks so that a copied field still points at its line; the new id, 0 when out of memory. */
static int copy_node(yaml_document_t* to, yaml_document_t* from, int id) {
  const yaml_node_t* n = yaml_document_get_node(from, id);
  int copy = 0;
  if (n->type == YAML_SCALAR_NODE) {
    copy = yaml_document_add_scalar(to, NULL, n->data.scalar.value, (int)n->data.scalar.length,
                                    n->data.scalar.style);
  } else if (n->type == YAML_SEQUENCE_NODE) {
    const int len = (int)(n->data.sequence.items.top - n->data.sequence.items.start);
    copy = yaml_document_add_sequence(to, NULL, n->data.sequence.style);
    for (int k = 0; copy && k < len; ++k) { /* adding nodes may move them: look `n` up again */
      const int item =
          copy_node(to, from, yaml_document_get_node(from, id)->data.sequence.items.start[k]);
      if (!item || !yaml_document_append_sequence_item(to, copy, item)) copy = 0;
    }
  } else if (n->type == YAML_MAPPING_NODE) {
    const int len = (int)(n->data.mapping.pairs.top - n->data.mapping.pairs.start);
    copy = yaml_document_add_mapping(to, NULL, n->data.mapping.style);
    for (int k = 0; copy && k < len; ++k) {
      const int key =
          copy_node(to, from, yaml_document_get_node(from, id)->data.mapping.pairs.start[k].key);
      const int value =
          key ? copy_node(to, from,
                          yaml_document_get_node(from, id)->data.mapping.pairs.start[k].value)
              : 0;
      if (!value || !yaml_document_append_mapping_pair(to, copy, key, value)) copy = 0;
    }
  }
  if (copy) {
    yaml_node_t* c = yaml_document_get_node(to, copy);
    const yaml_node_t* source = yaml_document_get_node(from, id);
    c->start_mark = source->start_mark;
    c->end_mark = source->end_mark;
  }
  return copy;
}

typedef struct {
  char key[64];
  int index; /* -1: none */
} path_step;

/* "links[0].modes" into {links, 0}, {modes, -1}; the number of steps, 0 if malformed. */
static int parse_path(const char* path, size_t length, path_step* steps, int capacity) {
  int n = 0;
  size_t i = 0;
  while (i < length) {
    if (n == capacity) return 0;
    path_step* st = &steps[n++];
    size_t k = 0;
    while (i < length && path[i] != '.' && path[i] != '[') {
      const char c = path[i++];
      if (!(c == '_' || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
            (c >= '0' && c <= '9')) ||
          k + 1 >= sizeof st->key)
        return 0;
      st->key[k++] = c;
    }
    st->key[k] = '\0';
    st->index = -1;
    if (k == 0) return 0;
    if (i < length && path[i] == '[') {
      char* end = NULL;
      const long index = strtol(path + i + 1, &end, 10);
      if (end == path + i + 1 || *end != ']' || index < 0 || index > 1000000) return 0;
      st->index = (int)index;
      i = (size_t)(end - path) + 1;
    }
    if (i < length) {
      if (path[i] != '.') return 0;
      if (++i == length) return 0;
    }
  }
  return n;
}

static int node_count(const yaml_document_t* doc) {
  return (int)(doc->nodes.top - doc->nodes.start);
}

/* From here on, what the document gains is the override's: its value and any field it adds (a
 * link list made before from the file's shared mapping keeps pointing at the file). */
static void override_nodes_begin(overriding* O) {
  if (!O->first_node) O->first_node = node_count(O->doc) + 1;
}

static int copy_value(overriding* O, yaml_document_t* from, int value) {
  override_nodes_begin(O);
  return copy_node(O->doc, from, value);
}

static int pair_count(const yaml_node_t* map) {
  return (int)(map->data.mapping.pairs.top - map->data.mapping.pairs.start);
}

/* Sets the field `steps` names under mapping `node` (a sequence of mappings: each of them) to a
 * copy of `value` of `from`; missing mappings on the way are made. `field` grows with the path for
 * messages. */
/* A field the file leaves to its default, added under node: the value itself when it is the
 * path's last step, else an empty mapping for the next step (*child). */
static f3r_status add_field(overriding* O, int node, const path_step* step, int last,
                            yaml_document_t* from, int value, const char* field, const char* text,
                            int* child) {
  if (step->index >= 0)
    return f3r_error_set(O->err, F3R_ERR_SCENE,
                         "--set %s: %s is not in %s, so [%d] has nothing to index", text, field,
                         O->path, step->index);
  override_nodes_begin(O);
  const int key =
      yaml_document_add_scalar(O->doc, NULL, (yaml_char_t*)step->key, -1, YAML_PLAIN_SCALAR_STYLE);
  *child = !key   ? 0
           : last ? copy_value(O, from, value)
                  : yaml_document_add_mapping(O->doc, NULL, YAML_BLOCK_MAPPING_STYLE);
  if (!*child || !yaml_document_append_mapping_pair(O->doc, node, key, *child))
    return f3r_error_set(O->err, F3R_ERR_MEMORY, "--set %s: out of memory", text);
  return F3R_OK;
}

/* One mapping for all three links (pair `found` of node, value `links`) becomes a list of three
 * copies, of which an indexed override then sets one. The list, or 0 out of memory. */
static int links_as_list(overriding* O, int node, int found, int links) {
  const int list = yaml_document_add_sequence(O->doc, NULL, YAML_BLOCK_SEQUENCE_STYLE);
  for (int k = 0; list && k < 3; ++k) {
    const int copy = copy_node(O->doc, O->doc, links);
    if (!copy || !yaml_document_append_sequence_item(O->doc, list, copy)) return 0;
  }
  if (list) yaml_document_get_node(O->doc, node)->data.mapping.pairs.start[found].value = list;
  return list;
}

static f3r_status set_field(overriding* O, int node, const path_step* steps, int count,
                            yaml_document_t* from, int value, char* field, size_t field_size,
                            const char* text) {
  const yaml_node_t* n = yaml_document_get_node(O->doc, node);
  if (n->type == YAML_SEQUENCE_NODE) { /* "links.modes": every link */
    const int len = (int)(n->data.sequence.items.top - n->data.sequence.items.start);
    const size_t mark = strlen(field);
    for (int k = 0; k < len; ++k) {
      snprintf(field + mark, field_size - mark, "[%d]", k);
      const int item = yaml_document_get_node(O->doc, node)->data.sequence.items.start[k];
      const f3r_status st = set_field(O, item, steps, count, from, value, field, field_size, text);
      if (st != F3R_OK) return st;
    }
    field[mark] = '\0';
    return F3R_OK;
  }
  if (n->type != YAML_MAPPING_NODE)
    return f3r_error_set(O->err, F3R_ERR_SCENE, "--set %s: %s is not a mapping in %s", text,
                         field[0] ? field : "the scene", O->path);
  const path_step* step = &steps[0];
  const size_t mark = strlen(field);
  snprintf(field + mark, field_size - mark, "%s%s", field[0] ? "." : "", step->key);
  int found = -1;
  for (int k = 0; k < pair_count(n) && found < 0; ++k) {
    const char* key = scalar(yaml_document_get_node(O->doc, n->data.mapping.pairs.start[k].key));
    if (key && !strcmp(key, step->key)) found = k;
  }
  const int last = count == 1;
  if (found < 0) { /* a field the file leaves to its default */
    int child = 0;
    const f3r_status st = add_field(O, node, step, last, from, value, field, text, &child);
    if (st != F3R_OK || last) return st;
    return set_field(O, child, steps + 1, count - 1, from, value, field, field_size, text);
  }
  int child = n->data.mapping.pairs.start[found].value;
  if (step->index >= 0) {
    const yaml_node_t* c = yaml_document_get_node(O->doc, child);
    if (c->type == YAML_MAPPING_NODE && !strcmp(step->key, "links") && mark == 0) {
      child = links_as_list(O, node, found, child);
      if (!child) return f3r_error_set(O->err, F3R_ERR_MEMORY, "--set %s: out of memory", text);
      c = yaml_document_get_node(O->doc, child);
    }
    if (c->type != YAML_SEQUENCE_NODE)
      return f3r_error_set(O->err, F3R_ERR_SCENE, "--set %s: %s in %s is not a list", text, field,
                           O->path);
    const int len = (int)(c->data.sequence.items.top - c->data.sequence.items.start);
    if (step->index >= len)
      return f3r_error_set(O->err, F3R_ERR_SCENE, "--set %s: %s has %d entries in %s (index 0..%d)",
                           text, field, len, O->path, len - 1);
    snprintf(field + strlen(field), field_size - strlen(field), "[%d]", step->index);
    if (last) {
      const int copy = copy_value(O, from, value);
      if (!copy) return f3r_error_set(O->err, F3R_ERR_MEMORY, "--set %s: out of memory", text);
      yaml_document_get_node(O->doc, child)->data.sequence.items.start[step->index] = copy;
      return F3R_OK;
    }
    child = c->data.sequence.items.start[step->index];
  } else if (last) {
    const int copy = copy_value(O, from, value);
    if (!copy) return f3r_error_set(O->err, F3R_ERR_MEMORY, "--set %s: out of memory", text);
    yaml_document_get_node(O->doc, node)->data.mapping.pairs.start[found].value = copy;
    return F3R_OK;
  }
  return set_field(O, child, steps + 1, count - 1, from, value, field, field_size, text);
}

f3r_status f3r_scene_apply_override(yaml_document_t* doc, const char* path, const char* text,
                                    int* first_node, int* last_node, f3r_error* err) {
  overriding context = {doc, path, err, 0};
  overriding* O = &context;
  const int root = 1;
  const char* eq = strchr(text, '=');
  path_step steps[16];
  const int count = eq ? parse_path(text, (size_t)(eq - text), steps, 16) : 0;
  if (!count)
    return f3r_error_set(
        O->err, F3R_ERR_SCENE,
        "--set %s: expected FIELD=VALUE with FIELD like links[0].modes or effects.payload.mass",
        text);
  if (!eq[1]) return f3r_error_set(O->err, F3R_ERR_SCENE, "--set %s: no value after '='", text);
  yaml_parser_t parser;
  yaml_document_t value;
  yaml_parser_initialize(&parser);
  yaml_parser_set_input_string(&parser, (const unsigned char*)(eq + 1), strlen(eq + 1));
  if (!yaml_parser_load(&parser, &value)) {
    const f3r_status st =
        f3r_error_set(O->err, F3R_ERR_SCENE, "--set %s: the value is not YAML: %s", text,
                      parser.problem ? parser.problem : "?");
    yaml_parser_delete(&parser);
    return st;
  }
  f3r_status st = F3R_OK;
  if (!yaml_document_get_root_node(&value)) {
    st = f3r_error_set(O->err, F3R_ERR_SCENE, "--set %s: no value after '='", text);
  } else {
    char field[256] = "";
    st = set_field(O, root, steps, count, &value, 1, field, sizeof field, text);
    *first_node = O->first_node;
    *last_node = O->first_node ? node_count(O->doc) : -1;
  }
  yaml_document_delete(&value);
  yaml_parser_delete(&parser);
  return st;
}

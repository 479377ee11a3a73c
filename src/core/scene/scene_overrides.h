/* Scene overrides, internal to the core (scene_yaml.c applies them, scene_overrides.c holds
 * them). */
#ifndef F3R_SCENE_OVERRIDES_H
#define F3R_SCENE_OVERRIDES_H

#include <yaml.h>

#include "flex3rpr/scene.h"

/* Applies one override, text "FIELD=VALUE" (VALUE is YAML: a number, a word, a [flow, list]),
 * to the scene document of `path` (for messages): a sequence of mappings on the way (links) has
 * each of them set, a field the file leaves out is added. The nodes it added are ids
 * *first_node .. *last_node (0 and -1 when none), so that a message about one of them can name
 * the override. */
f3r_status f3r_scene_apply_override(yaml_document_t* doc, const char* path, const char* text,
                                    int* first_node, int* last_node, f3r_error* err);

#endif

/* The scene layer's lists of names for messages (names.c). Private to the layer. */
#ifndef FLEX3RPR_SCENE_NAMES_H
#define FLEX3RPR_SCENE_NAMES_H

#include <stddef.h>

/* names[0..count) joined by separator ("a, b, c"; "erk or dirk") into list, cut short (but
 * terminated) when list is too small; returns list. */
const char* f3r_join_names(const char* const* names, int count, const char* separator, char* list,
                           size_t size);

#endif

/* The names of the scene's enums, one table each, indexed by the enum's value: the YAML loader,
 * the CLI and the node read and print them from here, so that each name is spelled once. */
#include <stdio.h>
#include <string.h>

#include "flex3rpr/kinds.h"
#include "flex3rpr/scene.h"
#include "names.h"

#define COUNT(table) ((int)(sizeof(table) / sizeof(table)[0]))

static const char* const link_model_names[] = {"rigid", "fixed_pinned", "fixed_free"};

/* index3 has a name, for messages, but no scene chooses it: a simulation rejects it. Only the
 * first SELECTABLE_FORMULATIONS names are choices. */
static const char* const formulation_names[] = {"dae", "minimal", "index3"};
#define SELECTABLE_FORMULATIONS 2

/* The tables are indexed by value: they must follow the enums' order. */
_Static_assert(F3R_LINK_RIGID == 0 && F3R_LINK_FIXED_PINNED == 1 && F3R_LINK_FIXED_FREE == 2,
               "link_model_names follows f3r_link_model");
_Static_assert(F3R_FORMULATION_DAE == 0 && F3R_FORMULATION_MINIMAL == 1 &&
                   F3R_FORMULATION_INDEX3 == 2,
               "formulation_names follows f3r_formulation");

static const char* name_of(const char* const* names, int count, int value) {
  return value >= 0 && value < count ? names[value] : "unknown";
}

static int value_of(const char* const* names, int count, const char* name) {
  for (int k = 0; name && k < count; ++k)
    if (!strcmp(name, names[k])) return k;
  return -1;
}

const char* f3r_join_names(const char* const* names, int count, const char* separator, char* list,
                           size_t size) {
  size_t used = 0;
  if (size) list[0] = '\0';
  for (int k = 0; k < count && used < size; ++k) {
    const int n = snprintf(list + used, size - used, "%s%s", k ? separator : "", names[k]);
    if (n < 0) break;
    used += (size_t)n;
  }
  return list;
}

static const char* join(const char* const* names, int count, char* list, size_t size) {
  return f3r_join_names(names, count, ", ", list, size);
}

/* The three functions scene.h declares for one enum: type_name, type_from_name and type_names.
 * named: how many of the table's names a value may have; chosen: how many a scene may choose. */
#define F3R_ENUM_NAMES(type, table, named, chosen)                                  \
  const char* type##_name(type value) { return name_of(table, named, (int)value); } \
  int type##_from_name(const char* name, type* value) {                             \
    const int k = value_of(table, chosen, name);                                    \
    if (k < 0) return -1;                                                           \
    *value = (type)k;                                                               \
    return 0;                                                                       \
  }                                                                                 \
  const char* type##_names(char* list, size_t size) { return join(table, chosen, list, size); }

F3R_ENUM_NAMES(f3r_link_model, link_model_names, COUNT(link_model_names), COUNT(link_model_names))
F3R_ENUM_NAMES(f3r_formulation, formulation_names, COUNT(formulation_names),
               SELECTABLE_FORMULATIONS)

/* The integrators' names are their table's (integrator_kinds.c), which may grow at run time. */
static int integrator_names(const char** names) {
  const int count = f3r_integrator_kind_count();
  for (int k = 0; k < count; ++k) names[k] = f3r_integrator_kind_at(k)->name;
  return count;
}

const char* f3r_integrator_name(f3r_integrator value) {
  const f3r_integrator_kind* kind = f3r_integrator_kind_at((int)value);
  return kind ? kind->name : "unknown";
}

int f3r_integrator_from_name(const char* name, f3r_integrator* value) {
  const char* names[F3R_INTEGRATOR_MAX_KINDS];
  const int k = value_of(names, integrator_names(names), name);
  if (k < 0) return -1;
  *value = (f3r_integrator)k;
  return 0;
}

const char* f3r_integrator_names(char* list, size_t size) {
  const char* names[F3R_INTEGRATOR_MAX_KINDS];
  return join(names, integrator_names(names), list, size);
}

/* The accuracy knob's measured solver relations (accuracy.h): one row per formulation,
 * integrator, Butcher table and tolerance measured by the work-precision benchmark. The rows are
 * data, written by bench/solver_table.py into solver_table.def; this file only lays them out. */
#include "flex3rpr/accuracy.h"

#define F3R_RELATIONS_SOURCE(text) const char f3r_solver_relations_source[] = text;
#define F3R_RELATION(...)
#include "solver_table.def"
#undef F3R_RELATIONS_SOURCE
#undef F3R_RELATION

#define F3R_RELATIONS_SOURCE(text)
#define F3R_RELATION(...) {__VA_ARGS__},
const f3r_solver_relation f3r_solver_relations[] = {
#include "solver_table.def"
};
#undef F3R_RELATIONS_SOURCE
#undef F3R_RELATION

const int f3r_solver_relation_count =
    (int)(sizeof f3r_solver_relations / sizeof f3r_solver_relations[0]);

/* The integrators (kinds.h): one row each, the only list of them. Their steppers are the solve
 * layer's (src/core/solve/stepper.c f3r_stepper_ops_of), in the same order. */
#include <string.h>

#include "flex3rpr/kinds.h"
#include "flex3rpr/scene.h"

#define BOTH ((1u << F3R_FORMULATION_DAE) | (1u << F3R_FORMULATION_MINIMAL))
#define MINIMAL (1u << F3R_FORMULATION_MINIMAL)

/* Those the benchmark measures (bench/solver_table.py): ARKODE's and erk_tables.c's pairs. */
static const char* const kExplicitTables[] = {"ARKODE_FEHLBERG_13_7_8",
                                              "ARKODE_DORMAND_PRINCE_7_4_5",
                                              "ARKODE_VERNER_8_5_6",
                                              "dormand_prince_8_5",
                                              "verner_8_7",
                                              "verner_9_8",
                                              NULL};
static const char* const kImplicitTables[] = {
    "ARKODE_KVAERNO_7_4_5", "ARKODE_ARK548L2SA_DIRK_8_4_5", "ARKODE_SDIRK_5_3_4", NULL};

static const f3r_integrator_kind kBuiltin[] = {
    {"ida", "SUNDIALS IDA, variable-order BDF", BOTH, 0, NULL, 1},
    {"erk", "SUNDIALS ARKODE ERKStep, explicit Runge-Kutta", MINIMAL, 1, kExplicitTables, 0},
    {"dirk", "SUNDIALS ARKODE ARKStep, diagonally implicit Runge-Kutta", MINIMAL, 0,
     kImplicitTables, 0}};

#define BUILTIN ((int)(sizeof kBuiltin / sizeof kBuiltin[0]))
_Static_assert(F3R_INTEGRATOR_IDA == 0 && F3R_INTEGRATOR_ERK == 1 && F3R_INTEGRATOR_DIRK == 2,
               "kBuiltin follows f3r_integrator");

static const f3r_integrator_kind* added[F3R_INTEGRATOR_MAX_KINDS];
static int added_count;

int f3r_integrator_kind_count(void) { return BUILTIN + added_count; }

const f3r_integrator_kind* f3r_integrator_kind_at(int k) {
  if (k >= 0 && k < BUILTIN) return &kBuiltin[k];
  if (k >= BUILTIN && k < BUILTIN + added_count) return added[k - BUILTIN];
  return NULL;
}

int f3r_integrator_kind_add(const f3r_integrator_kind* kind) {
  if (!kind || !kind->name || !kind->description || !(kind->formulations & BOTH) ||
      f3r_integrator_kind_count() >= F3R_INTEGRATOR_MAX_KINDS)
    return -1;
  for (int k = 0; k < f3r_integrator_kind_count(); ++k)
    if (!strcmp(f3r_integrator_kind_at(k)->name, kind->name)) return -1;
  added[added_count++] = kind;
  return f3r_integrator_kind_count() - 1;
}

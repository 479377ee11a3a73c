/* Explicit Runge-Kutta pairs missing from SUNDIALS 6.4 (see erk_tables.h). Coefficients are
 * copied digit for digit from the sources named per table (30-40 significant digits; the compiler
 * rounds each literal to the nearest double). Unlisted entries are zero. Checked by
 * scripts/ci/butcher_tables.py: order conditions to order 9, measured orders, stability. */
#include "erk_tables.h"

#include <string.h>

#define IJ(s, i, j) [(i) * (s) + (j)] /* designated initializer of A[i][j], s stages */

#include "erk_tables.def"

const f3r_erk_table* f3r_erk_table_find(const char* name) {
  if (!name) return NULL;
  for (int k = 0; k < f3r_erk_table_count; ++k)
    if (strcmp(f3r_erk_tables[k].name, name) == 0) return &f3r_erk_tables[k];
  return NULL;
}

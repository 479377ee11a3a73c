/* Explicit Runge-Kutta pairs that SUNDIALS 6.4 lacks, as plain data. The caller builds the
 * ARKODE table: ARKodeButcherTable_Create(stages, order, embedded_order, c, A, b, b_embedded).
 * scripts/ci/butcher_tables.py parses erk_tables.c and checks every table (order conditions,
 * measured convergence order, stability on the imaginary axis). Private. */
#ifndef FLEX3RPR_ERK_TABLES_H
#define FLEX3RPR_ERK_TABLES_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  const char* name;   /* e.g. "dormand_prince_8_5" */
  const char* source; /* where the coefficients come from (paper + where copied from) */
  int stages, order, embedded_order;
  const double* A;          /* stages x stages, row-major, strictly lower triangular */
  const double* b;          /* stages: the method's weights */
  const double* b_embedded; /* stages: the embedded method's weights */
  const double* c;          /* stages */
} f3r_erk_table;

extern const f3r_erk_table f3r_erk_tables[];
extern const int f3r_erk_table_count;

/* The table called name, NULL when there is none. */
const f3r_erk_table* f3r_erk_table_find(const char* name);

#ifdef __cplusplus
}
#endif

#endif

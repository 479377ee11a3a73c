/* The columns of a run's outputs, as the CLI's CSV writes them and the Python module returns them
 * (one definition, so that both give the same numbers): t, q, the tip deflections, their rates, the
 * loop forces, the energies, the constraint residual and, with end stops, the stops' forces. */
#ifndef FLEX3RPR_OUTPUT_COLUMNS_H
#define FLEX3RPR_OUTPUT_COLUMNS_H

#include "flex3rpr/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Most columns any model has. */
#define F3R_OUTPUT_MAX_COLUMNS (2 * (F3R_MAX_Q + 3) + F3R_NCON + 8)
#define F3R_OUTPUT_NAME 24

/* The number of columns of the model's outputs. */
int f3r_output_columns(const f3r_model* model);
/* Column k's name into name (F3R_OUTPUT_NAME chars), and the significant digits the CSV writes
 * it with. */
int f3r_output_column_name(const f3r_model* model, int k, char* name);
/* The outputs' values in column order; returns their count. */
int f3r_output_row(const f3r_model* model, const f3r_outputs* out, double* values);

#ifdef __cplusplus
}
#endif
#endif

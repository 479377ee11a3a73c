/* flex3rpr_sim's CSV: the header and rows of the output columns (output_columns.h) and the
 * sensors' columns, each value at its column's significant digits (csv_number.h). */
#ifndef FLEX3RPR_CLI_CSV_ROWS_H
#define FLEX3RPR_CLI_CSV_ROWS_H

#include <stddef.h>
#include <stdio.h>

#include "flex3rpr/model.h"
#include "flex3rpr/sensors.h"
#include "flex3rpr/sim.h"

/* bytes of the CSV's stdio buffer: about 300 rows of paper simulation 3 (800 bytes each) */
#define CSV_BUFFER_BYTES (256 * 1024)

void cli_csv_header(FILE* f, const f3r_model* m, const f3r_sensors* sensors);
/* One row, formed in a buffer and written at once. */
void cli_csv_row(FILE* f, const f3r_model* m, const f3r_outputs* o, const f3r_sensors* sensors);
/* rows (size bytes, a whole CSV kept in memory) into path; 0, or 1 with the failure said. */
int cli_write_rows(const char* path, const char* rows, size_t size);

#endif

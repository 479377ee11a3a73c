/* flex3rpr_sim's CSV (csv_rows.h). */
#include "csv_rows.h"

#include "cli_options.h"
#include "flex3rpr/csv_number.h"
#include "flex3rpr/output_columns.h"
#include "sensor_columns.h"

/* The columns (output_columns.h) and the significant digits each is written with, per model. */
typedef struct {
  const f3r_model* model;
  int count;
  int digits[F3R_OUTPUT_MAX_COLUMNS];
} column_digits;

static const column_digits* digits_of(const f3r_model* m) {
  static column_digits cached;
  if (cached.model != m) {
    char name[F3R_OUTPUT_NAME];
    cached.model = m;
    cached.count = f3r_output_columns(m);
    for (int k = 0; k < cached.count; ++k) cached.digits[k] = f3r_output_column_name(m, k, name);
  }
  return &cached;
}

void cli_csv_header(FILE* f, const f3r_model* m, const f3r_sensors* sensors) {
  char name[F3R_OUTPUT_NAME];
  const int count = f3r_output_columns(m);
  for (int k = 0; k < count; ++k) {
    f3r_output_column_name(m, k, name);
    fprintf(f, "%s%s", k ? "," : "", name);
  }
  f3r_cli_sensor_header(f, sensors);
  fprintf(f, "\n");
}

/* One row, formed in a buffer and written at once (a call to stdio a number took a fifth of the
 * writing); ",x" with x as "%.*g" (csv_number.h: the same text, 6 times faster). */
void cli_csv_row(FILE* f, const f3r_model* m, const f3r_outputs* o, const f3r_sensors* sensors) {
  char row[F3R_OUTPUT_MAX_COLUMNS * (F3R_FORMAT_G_SIZE + 1) + F3R_SENSOR_ROW_SIZE];
  double values[F3R_OUTPUT_MAX_COLUMNS];
  const column_digits* digits = digits_of(m);
  f3r_output_row(m, o, values);
  char* end = row;
  for (int k = 0; k < digits->count; ++k) {
    if (k) *end++ = ',';
    end += f3r_format_g(end, values[k], digits->digits[k]);
  }
  end = f3r_cli_sensor_row(end, sensors);
  *end++ = '\n';
  fwrite(row, 1, (size_t)(end - row), f);
}

/* The CSV of the run written, from memory. */
int cli_write_rows(const char* path, const char* rows, size_t size) {
  FILE* f = fopen(path, "w");
  if (!f || fwrite(rows, 1, size, f) != size || fclose(f)) {
    cli_fail("io", "cannot write %s", path);
    return 1;
  }
  return 0;
}

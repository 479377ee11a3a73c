/* The CLI's sensor columns (sensor_columns.h). */
#include "sensor_columns.h"

#include "flex3rpr/csv_number.h"

f3r_status f3r_cli_sensors_start(const f3r_model* model, f3r_sim* sim, f3r_sensors** sensors,
                                 f3r_error* err) {
  *sensors = NULL;
  const f3r_sensors_scene* config = &f3r_model_scene(model)->sensors;
  if (!f3r_sensors_any(config)) return F3R_OK;
  f3r_status st = f3r_sensors_create(model, config, sensors, err);
  if (st == F3R_OK) st = f3r_sensors_update(*sensors, f3r_sim_outputs(sim), err);
  return st;
}

void f3r_cli_sensor_header(FILE* f, const f3r_sensors* s) {
  for (int c = 0; s && c < f3r_sensors_columns(s); ++c)
    fprintf(f, ",%s", f3r_sensors_column_name(s, c));
}

char* f3r_cli_sensor_row(char* end, const f3r_sensors* s) {
  if (!s) return end;
  double values[F3R_SENSOR_MAX_KINDS * F3R_SENSOR_MAX_CHANNELS];
  const int n = f3r_sensors_row(s, values);
  for (int c = 0; c < n; ++c) {
    *end++ = ',';
    end += f3r_format_g(end, values[c], 15);
  }
  return end;
}

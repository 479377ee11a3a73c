/* The CLI's sensor columns (sensor_columns.h). */
#include "sensor_columns.h"

#include "flex3rpr/csv_number.h"

static const char* const kNames[F3R_SENSOR_KINDS][F3R_SENSOR_MAX_CHANNELS] = {
    {"enc_rho_1", "enc_rho_2", "enc_rho_3", "enc_theta_1", "enc_theta_2", "enc_theta_3"},
    {"strain_1", "strain_2", "strain_3"},
    {"accel_x", "accel_y", "gyro_z"}};

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
  if (!s) return;
  for (int k = 0; k < F3R_SENSOR_KINDS; ++k) {
    const f3r_sensor_reading* r = f3r_sensors_reading(s, k);
    if (!r->enabled) continue;
    for (int c = 0; c < r->channels; ++c) fprintf(f, ",%s", kNames[k][c]);
  }
}

char* f3r_cli_sensor_row(char* end, const f3r_sensors* s) {
  if (!s) return end;
  for (int k = 0; k < F3R_SENSOR_KINDS; ++k) {
    const f3r_sensor_reading* r = f3r_sensors_reading(s, k);
    if (!r->enabled) continue;
    for (int c = 0; c < r->channels; ++c) {
      *end++ = ',';
      end += f3r_format_g(end, r->value[c], 15);
    }
  }
  return end;
}

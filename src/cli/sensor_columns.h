/* The CLI's sensor columns (docs/cli.md): the scene's sensors' readings after the CSV's other
 * columns, present only when a sensor is enabled. */
#ifndef F3R_CLI_SENSOR_COLUMNS_H
#define F3R_CLI_SENSOR_COLUMNS_H

#include <stdio.h>

#include "flex3rpr/sensors.h"

/* The most characters a row's sensor columns take. */
#define F3R_SENSOR_ROW_SIZE (F3R_SENSOR_MAX_KINDS * F3R_SENSOR_MAX_CHANNELS * 33)

/* Creates the model's sensors when its scene enables any (*sensors NULL otherwise) and takes
 * their samples at the simulation's current state. */
f3r_status f3r_cli_sensors_start(const f3r_model* model, f3r_sim* sim, f3r_sensors** sensors,
                                 f3r_error* err);

/* ",enc_rho_1,...": the enabled sensors' column names (nothing for NULL). */
void f3r_cli_sensor_header(FILE* f, const f3r_sensors* sensors);

/* The readings as ",x" each at end; returns the new end (end for NULL). */
char* f3r_cli_sensor_row(char* end, const f3r_sensors* sensors);

#endif

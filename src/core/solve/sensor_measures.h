/* What each sensor kind measures (sensor_measures.c), by its index in the kinds' table. Private. */
#ifndef FLEX3RPR_SENSOR_MEASURES_H
#define FLEX3RPR_SENSOR_MEASURES_H

#include "flex3rpr/sensors.h"

/* The measurement of kind k; NULL outside the table. */
const f3r_sensor_measure* f3r_sensor_measure_of(int kind);

#endif

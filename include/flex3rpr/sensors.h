/* f3r_sensors: the scene's simulated sensors (scene.h f3r_sensors_scene, docs/scenes.md), shared
 * by the CLI, the node and any other shell: sampling, Gaussian noise, quantisation and delay.
 * The kinds, their channels and names are the table of kinds.h; what each measures is
 * sensor_measures.c's (f3r_sensors_register adds one).
 *
 * Channels of the built-in sensors (F3R_SENSOR_*):
 *   encoders       6: rho_1..3 (m), theta_1..3 (rad)
 *   strain gauges  3: the bending strain at the root (clamp, x = 0) of link 1..3,
 *                     eps_i = (d/2) w_i''(0), w_i''(0) = sum_j psi_j''(0) eta_j / l^2: the axial
 *                     strain of the fibre on the -n side of the link (n = (-sin theta_i,
 *                     cos theta_i), the direction w is positive along), tension positive. A
 *                     rigid link reads 0 (plus noise).
 *   accelerometer  3: the specific force of the platform centre P in the platform frame,
 *                     f = R(phi_p)^T (a_P - g) (m/s^2, in-plane x and y; the scene's gravity
 *                     (0, 0, -9.81) is normal to the plane and gives no in-plane part), and
 *                     the angular rate phi_p' (rad/s) of a z gyro.
 *
 * Sample k of a sensor is due at t = k / rate; f3r_sensors_update takes it at the first call at
 * or after that time, from the state of that call (so with a rate that divides the output rate
 * every sample is taken exactly on time). The value is truth + noise * N(0, 1), then rounded to
 * a multiple of resolution. The N(0, 1) draw is a function of (seed, sensor, channel, k) alone (a
 * counter-based generator), so readings never depend on wall time, message timing or on how
 * often update is called. The reading reports sample k - delay; before delay samples exist it
 * reports sample 0 (the delay line starts full of the first measurement). Calls that skip
 * sample instants (a rate above the update rate) take the skipped samples from the same state.
 * Nothing is allocated after f3r_sensors_create. */
#ifndef FLEX3RPR_SENSORS_H
#define FLEX3RPR_SENSORS_H

#include "flex3rpr/sim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The built-in kinds' indices in the table (sensor_kinds.c). */
enum { F3R_SENSOR_ENCODERS = 0, F3R_SENSOR_STRAIN = 1, F3R_SENSOR_ACCELEROMETER = 2 };

/* What a measurement sees: the state, its accelerations when the kind asks for them (solved once
 * per update for all kinds), and the constants its prepare computed for the model. */
#define F3R_SENSOR_CONSTANTS (3 * F3R_MAX_MODES)
typedef struct {
  const f3r_model* model;
  const f3r_outputs* out;
  const double* a;         /* q'' at out.t; NULL unless needs_accelerations */
  const double* constants; /* F3R_SENSOR_CONSTANTS, from prepare (zeros without one) */
} f3r_sensor_input;

typedef struct {
  int needs_accelerations;
  void (*prepare)(const f3r_model* model, double* constants); /* NULL: none */
  void (*measure)(const f3r_sensor_input* in, double* value); /* the exact channels */
} f3r_sensor_measure;

/* Adds a sensor kind: its descriptor to the table (f3r_sensor_kind_add) and its measurement, at
 * the index it returns in *index; scenes then name it under sensors:, and every shell lists its
 * channels. F3R_ERR_ARGUMENT when the table refuses it. Not thread-safe: before the first scene.
 * Both must outlive every scene and simulation. */
f3r_status f3r_sensors_register(const f3r_sensor_kind* kind, const f3r_sensor_measure* measure,
                                int* index, f3r_error* err);

typedef struct {
  int enabled;
  int channels;                          /* the kind's (kinds.h) */
  long sample;                           /* k of the sample reported; -1 before the first */
  double measured_at;                    /* t of the state it was taken from (s) */
  long updated_at_sample;                /* the newest sample taken (k), -1 before the first */
  int fresh;                             /* 1: the last update took a new sample */
  double value[F3R_SENSOR_MAX_CHANNELS]; /* the reading */
} f3r_sensor_reading;

typedef struct f3r_sensors f3r_sensors;

/* For the model's sensors as the scene (or a caller's copy of it) sets them. */
f3r_status f3r_sensors_create(const f3r_model* model, const f3r_sensors_scene* config,
                              f3r_sensors** sensors, f3r_error* err);
void f3r_sensors_destroy(f3r_sensors* sensors);

/* Forgets every sample (as at t = 0 before the first update). */
void f3r_sensors_reset(f3r_sensors* sensors);

/* Makes `to` (created for the same model and sensors) read as `from` does: its samples, delay
 * lines and readings, so that a session can put its sensors back after a failed step. The noise
 * is a function of the sample number, so nothing else needs keeping. */
void f3r_sensors_copy(f3r_sensors* to, const f3r_sensors* from);

/* 1 when any sensor is enabled. */
int f3r_sensors_any(const f3r_sensors_scene* config);

/* Takes the samples due at out->t (a state of the sensors' model). Errors: F3R_ERR_ARGUMENT for
 * a time before the last update's, F3R_ERR_SINGULAR when the accelerations cannot be solved. */
f3r_status f3r_sensors_update(f3r_sensors* sensors, const f3r_outputs* out, f3r_error* err);

/* The reading of sensor kind (F3R_SENSOR_*, or a registered one's index); NULL outside the
 * table. */
const f3r_sensor_reading* f3r_sensors_reading(const f3r_sensors* sensors, int kind);

/* The enabled sensors' channels as columns, kind by kind in the table's order: the CLI's CSV,
 * Python's Sim.sensors. count, the name of column i (kinds.h column), and the readings into
 * values (count of them). */
int f3r_sensors_columns(const f3r_sensors* sensors);
const char* f3r_sensors_column_name(const f3r_sensors* sensors, int column);
int f3r_sensors_row(const f3r_sensors* sensors, double* values);

/* The exact values every channel would measure at out (no noise, quantisation or delay), each
 * sensor's channels in value[kind][...] (enabled kinds only). */
f3r_status f3r_sensors_truth(f3r_sensors* sensors, const f3r_outputs* out,
                             double value[F3R_SENSOR_MAX_KINDS][F3R_SENSOR_MAX_CHANNELS],
                             f3r_error* err);

/* The gauge of link i as a row over its modal coordinates: eps_i = sum_j c[j] eta_ij, c[j] =
 * (d/2) psi_j''(0) / l^2 (1/m), link_modes values (0 for a rigid link); returns that count. */
int f3r_sensors_strain_row(const f3r_model* model, int link, double* c);

/* The standard normal draw of (seed, kind, channel, sample): what noise multiplies. */
double f3r_sensor_normal(int seed, int kind, int channel, long sample);

#ifdef __cplusplus
}
#endif
#endif

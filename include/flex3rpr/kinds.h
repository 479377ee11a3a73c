/* The families a scene chooses from by name, one descriptor table each, which every shell reads
 * (the scene loader, the CLI's columns and options, the node's topics, Python's names):
 *
 *   sensors       name, channels, channel names, scene keys of noise and resolution, topic
 *   integrators   name, description, the formulations each integrates, Butcher tables
 *
 * A built-in kind is one row of sensor_kinds.c or integrator_kinds.c (src/core/scene/) plus its
 * implementation in the solve layer (sensors.h f3r_sensors_register, stepper.h
 * f3r_integrators_register); docs/design/adding_a_kind.md walks through both. The tables are the
 * scene layer's, below the physics, so the loader checks names and keys without knowing how a
 * sensor measures or an integrator steps.
 *
 * Kinds registered at run time (as MuJoCo's plugins) go through the solve layer's register
 * functions, which pair the descriptor with its implementation. Registering is not thread-safe:
 * do it before loading the first scene. */
#ifndef FLEX3RPR_KINDS_H
#define FLEX3RPR_KINDS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define F3R_SENSOR_MAX_KINDS 8
#define F3R_SENSOR_MAX_CHANNELS 6

typedef struct {
  const char* name;    /* sensors.NAME in a scene, the node's ~sensors/NAME/... */
  const char* topic;   /* the node's topic, ~TOPIC */
  const char* summary; /* one line: what it measures */
  int channels;        /* 1..F3R_SENSOR_MAX_CHANNELS */
  const char* column[F3R_SENSOR_MAX_CHANNELS]; /* the CSV's and Python's column names */
  const char* joint[F3R_SENSOR_MAX_CHANNELS];  /* the URDF joint each channel measures, when all
                                                * do (the node publishes a JointState); NULL */
  const char* noise_key[2];      /* scene keys of noise[g]; NULL where there is no group g */
  const char* resolution_key[2]; /* scene keys of resolution[g] */
  unsigned char group[F3R_SENSOR_MAX_CHANNELS]; /* g of each channel: its noise and quantum */
} f3r_sensor_kind;

/* The sensor kinds: built-ins first, in F3R_SENSOR_* order (sensors.h), then registered ones. */
int f3r_sensor_kind_count(void);
const f3r_sensor_kind* f3r_sensor_kind_at(int kind); /* NULL outside 0..count-1 */
int f3r_sensor_kind_find(const char* name);          /* its index, or -1 */
/* "encoders, strain_gauges, accelerometer" into list (terminated, cut short); returns list. */
const char* f3r_sensor_kind_names(char* list, size_t size);
/* Appends a kind (copied by pointer: it must outlive the process's scenes); its index, or -1 when
 * the table is full, the name is taken or the descriptor is malformed. The solve layer's
 * f3r_sensors_register calls it beside its measurement. */
int f3r_sensor_kind_add(const f3r_sensor_kind* kind);

#define F3R_INTEGRATOR_MAX_KINDS 8

typedef struct {
  const char* name;          /* solver.integrator: NAME, the CLI's --integrator NAME */
  const char* description;   /* for summaries: "SUNDIALS ARKODE ERKStep, explicit RK" */
  unsigned formulations;     /* 1u << f3r_formulation for each it integrates */
  int explicit_method;       /* 1: explicit, its cost grows with the stiffest mode */
  const char* const* tables; /* the Butcher tables it offers by name, NULL-ended, the first
                                  * its default; NULL when it takes none */
  int has_order;             /* 1: solver.max_order applies (a BDF method) */
} f3r_integrator_kind;

/* The integrators: built-ins first, in F3R_INTEGRATOR_* order (scene.h), then registered ones. */
int f3r_integrator_kind_count(void);
const f3r_integrator_kind* f3r_integrator_kind_at(int kind); /* NULL outside 0..count-1 */
/* Appends an integrator; its index, or -1 when full, the name is taken or it names no
 * formulation. The solve layer's f3r_integrators_register calls it beside the stepper. */
int f3r_integrator_kind_add(const f3r_integrator_kind* kind);

#ifdef __cplusplus
}
#endif
#endif

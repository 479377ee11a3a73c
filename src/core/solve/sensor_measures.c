/* The built-in sensors' exact measurements (sensors.h has their definitions), in the order of
 * the kinds' table (src/core/scene/sensor_kinds.c), and the slots of registered ones. */
#include "sensor_measures.h"

#include <math.h>

#include "beam_basis.h"
#include "model_layout.h"

/* encoders: rho_i, theta_i */
static void encoders(const f3r_sensor_input* in, double* value) {
  for (int j = 0; j < F3R_Q_LEG_JOINTS; ++j) value[j] = in->out->q[j];
}

/* strain gauges: the rows of f3r_sensors_strain_row, link i's at constants[i * F3R_MAX_MODES] */
static void strain_rows(const f3r_model* m, double* constants) {
  for (int i = 0; i < 3; ++i) f3r_sensors_strain_row(m, i, constants + i * F3R_MAX_MODES);
}

static void strain(const f3r_sensor_input* in, double* value) {
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &in->model->link[i];
    const double* row = in->constants + i * F3R_MAX_MODES;
    double eps = 0.0;
    if (lp->model != F3R_LINK_RIGID)
      for (int j = 0; j < lp->modes; ++j) eps += row[j] * in->out->q[lp->eta_index + j];
    value[i] = eps;
  }
}

/* accelerometer: the specific force of P in the platform frame and the z gyro */
static void accelerometer(const f3r_sensor_input* in, double* value) {
  const f3r_model* m = in->model;
  const double fx = in->a[F3R_Q_X] - m->gravity[0], fy = in->a[F3R_Q_Y] - m->gravity[1];
  const double c = cos(in->out->q[F3R_Q_PHI]), sn = sin(in->out->q[F3R_Q_PHI]);
  value[0] = c * fx + sn * fy;
  value[1] = -sn * fx + c * fy;
  value[2] = in->out->v[F3R_Q_PHI];
}

static const f3r_sensor_measure kEncoders = {0, NULL, encoders};
static const f3r_sensor_measure kStrain = {0, strain_rows, strain};
static const f3r_sensor_measure kAccelerometer = {1, NULL, accelerometer};

static const f3r_sensor_measure* measures[F3R_SENSOR_MAX_KINDS] = {&kEncoders, &kStrain,
                                                                   &kAccelerometer};

const f3r_sensor_measure* f3r_sensor_measure_of(int kind) {
  return kind >= 0 && kind < f3r_sensor_kind_count() ? measures[kind] : NULL;
}

int f3r_sensors_strain_row(const f3r_model* m, int link, double* c) {
  const f3r_link_params* lp = &m->link[link];
  if (lp->model == F3R_LINK_RIGID) return 0;
  const double l = m->link_length, half = 0.5 * m->scene.link_diameter;
  for (int j = 0; j < lp->modes; ++j) {
    double dd = 0.0;
    f3r_beam_basis_eval(&m->basis[link], j, 0.0, NULL, NULL, &dd);
    c[j] = half * dd / (l * l);
  }
  return lp->modes;
}

f3r_status f3r_sensors_register(const f3r_sensor_kind* kind, const f3r_sensor_measure* measure,
                                int* index, f3r_error* err) {
  const int k = measure && measure->measure ? f3r_sensor_kind_add(kind) : -1;
  if (k < 0)
    return f3r_error_set(err, F3R_ERR_ARGUMENT,
                         "f3r_sensors_register: '%s' refused (no measurement, a name taken, a "
                         "malformed descriptor or %d kinds already)",
                         kind && kind->name ? kind->name : "(null)", F3R_SENSOR_MAX_KINDS);
  measures[k] = measure;
  *index = k;
  return F3R_OK;
}

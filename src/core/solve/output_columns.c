/* The columns of a run's outputs (output_columns.h). */
#include "flex3rpr/output_columns.h"

#include <stdio.h>

/* Walks the columns in order: names (when name_of is not NULL, for column `want`) or values. */
static int walk(const f3r_model* m, const f3r_outputs* o, double* values, int want, char* name) {
  static const char* rigid[9] = {"rho_1",   "rho_2", "rho_3", "theta_1", "theta_2",
                                 "theta_3", "x_p",   "y_p",   "phi_p"};
  static const char* tail[4] = {"kinetic_energy", "potential_energy", "external_work",
                                "constraint_residual"};
  int k = 0, digits = 15;
#define COLUMN(value, precision, ...)               \
  do {                                              \
    if (values) values[k] = (value);                \
    if (name && k == want) {                        \
      snprintf(name, F3R_OUTPUT_NAME, __VA_ARGS__); \
      digits = (precision);                         \
    }                                               \
    ++k;                                            \
  } while (0)
  COLUMN(o ? o->t : 0.0, 10, "t");
  for (int pass = 0; pass < 2; ++pass) {
    const char* suffix = pass ? "_dot" : "";
    const double* x = o ? (pass ? o->v : o->q) : NULL;
    for (int n = 0; n < F3R_Q_MODAL; ++n) COLUMN(x ? x[n] : 0.0, 15, "%s%s", rigid[n], suffix);
    int n = F3R_Q_MODAL;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < f3r_model_link(m, i)->modes; ++j, ++n)
        COLUMN(x ? x[n] : 0.0, 15, "eta_%d_%d%s", i + 1, j + 1, suffix);
    const double* w = o ? (pass ? o->tip_deflection_rate : o->tip_deflection) : NULL;
    for (int i = 0; i < 3; ++i) COLUMN(w ? w[i] : 0.0, 15, "w_tip_%d%s", i + 1, suffix);
  }
  for (int c = 0; c < F3R_NCON; ++c)
    COLUMN(o ? o->lambda[c] : 0.0, 10, "lambda_%d%c", c / 2 + 1, c % 2 ? 'y' : 'x');
  const double energies[4] = {o ? o->kinetic_energy : 0.0, o ? o->potential_energy : 0.0,
                              o ? o->external_work : 0.0, o ? o->constraint_residual : 0.0};
  for (int c = 0; c < 4; ++c) COLUMN(energies[c], c < 3 ? 15 : 3, "%s", tail[c]);
  /* with end stops: each stop's force on its leg (N, the contact's multiplier; 0 when free) */
  if (f3r_model_scene(m)->end_stops)
    for (int i = 0; i < 3; ++i) COLUMN(o ? o->stop_force[i] : 0.0, 10, "stop_force_%d", i + 1);
#undef COLUMN
  return name ? digits : k;
}

int f3r_output_columns(const f3r_model* model) { return walk(model, NULL, NULL, -1, NULL); }

int f3r_output_column_name(const f3r_model* model, int k, char* name) {
  return walk(model, NULL, NULL, k, name);
}

int f3r_output_row(const f3r_model* model, const f3r_outputs* out, double* values) {
  return walk(model, out, values, -1, NULL);
}

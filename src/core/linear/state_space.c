/* The linear model as a state-space system (include/flex3rpr/linear.h): A and B from
 * f3r_linearise's M, D, K and U; C from the loop closure's exact derivative at the operating
 * point. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "linear_parts.h"
#include "dense.h"
#include "model_layout.h"

void f3r_state_space_destroy(f3r_state_space* ss) { free(ss); }

/* One allocation: the struct, then A, B, C, D, x0 (doubles), then the state names. */
static f3r_state_space* state_space_alloc(int nx) {
  const size_t doubles = (size_t)nx * nx + (size_t)nx * F3R_SS_INPUTS +
                         (size_t)F3R_SS_OUTPUTS * nx + F3R_SS_OUTPUTS * F3R_SS_INPUTS + (size_t)nx;
  const size_t head = (sizeof(f3r_state_space) + sizeof(double) - 1) / sizeof(double);
  double* block = calloc(1, (head + doubles) * sizeof(double) + (size_t)nx * F3R_SS_NAME);
  f3r_state_space* ss = (f3r_state_space*)block;
  if (!ss) return NULL;
  ss->nx = nx;
  ss->nu = F3R_SS_INPUTS;
  ss->ny = F3R_SS_OUTPUTS;
  ss->A = block + head;
  ss->B = ss->A + (size_t)nx * nx;
  ss->C = ss->B + (size_t)nx * F3R_SS_INPUTS;
  ss->D = ss->C + (size_t)F3R_SS_OUTPUTS * nx;
  ss->x0 = ss->D + F3R_SS_OUTPUTS * F3R_SS_INPUTS;
  ss->state_names = (char(*)[F3R_SS_NAME])(ss->x0 + nx);
  return ss;
}

static void name_everything(const f3r_model* m, f3r_state_space* ss) {
  const int n = ss->nx / 2;
  static const char* pose[3] = {"x_p", "y_p", "phi_p"};
  for (int half = 0; half < 2; ++half) {
    const char* suffix = half ? "_rate" : "";
    char(*name)[F3R_SS_NAME] = ss->state_names + half * n;
    for (int k = 0; k < 3; ++k) snprintf(name[k], F3R_SS_NAME, "%s%s", pose[k], suffix);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < m->link[i].modes; ++j)
        snprintf(name[m->link[i].eta_index + j - F3R_Q_INDEPENDENT], F3R_SS_NAME, "eta_%d_%d%s",
                 i + 1, j + 1, suffix);
  }
  for (int i = 0; i < 3; ++i) {
    snprintf(ss->input_names[i], F3R_SS_NAME, "leg_force_%d", i + 1);
    snprintf(ss->input_names[3 + i], F3R_SS_NAME, "cylinder_torque_%d", i + 1);
    snprintf(ss->output_names[i], F3R_SS_NAME, "rho_%d", i + 1);
    snprintf(ss->output_names[3 + i], F3R_SS_NAME, "theta_%d", i + 1);
    snprintf(ss->output_names[6 + i], F3R_SS_NAME, "%s", pose[i]);
    snprintf(ss->output_names[9 + i], F3R_SS_NAME, "tip_deflection_%d", i + 1);
  }
}

/* C = [dy/dz 0] and y0 at the operating point q0 (closed, zero deflection). The rho and theta
 * rows are the velocity closure applied to unit rates of each z_k: rho' = dRho/dz z', exactly. */
static void outputs(const f3r_model* m, const double* q0, f3r_state_space* ss) {
  const int n = ss->nx / 2, ny = ss->ny;
  for (int i = 0; i < 3; ++i) {
    ss->y0[i] = q0[F3R_Q_RHO + i];
    ss->y0[3 + i] = q0[F3R_Q_THETA + i];
    ss->y0[6 + i] = q0[F3R_Q_X + i];
    ss->y0[9 + i] = f3r_model_tip_deflection(m, q0, i);
  }
  for (int k = 0; k < n; ++k) {
    double rate[F3R_MAX_Q] = {0};
    rate[F3R_Q_INDEPENDENT + k] = 1.0;
    f3r_model_close_loop_rates(m, q0, rate);
    for (int i = 0; i < 3; ++i) {
      F3R_AT(ss->C, ny, i, k) = rate[F3R_Q_RHO + i];
      F3R_AT(ss->C, ny, 3 + i, k) = rate[F3R_Q_THETA + i];
      F3R_AT(ss->C, ny, 9 + i, k) = f3r_model_tip_deflection(m, rate, i);
    }
    if (k < 3) F3R_AT(ss->C, ny, 6 + k, k) = 1.0;
  }
}

f3r_status f3r_state_space_create(const f3r_model* model, f3r_state_space** out, f3r_error* err) {
  if (!model || !out)
    return f3r_error_set(err, F3R_ERR_ARGUMENT, "f3r_state_space_create: NULL argument");
  *out = NULL;
  f3r_linear_model* lin = NULL;
  f3r_status st = f3r_linearise(model, &lin, err);
  if (st != F3R_OK) return st;
  const int n = lin->n, nx = 2 * n;
  f3r_state_space* ss = state_space_alloc(nx);
  double* L = malloc(((size_t)n * n + (size_t)n) * sizeof(double));
  double* col = L ? L + (size_t)n * n : NULL;
  if (!ss || !L) {
    st = f3r_error_set(err, F3R_ERR_MEMORY, "state space: out of memory");
    goto done;
  }
  if ((st = f3r_linear_mass_factor(lin, L, "state space", err)) != F3R_OK) goto done;
  for (int k = 0; k < n; ++k) F3R_AT(ss->A, nx, k, n + k) = 1.0;
  /* Lower block rows: -M^-1 K and -M^-1 D, a column at a time; B's from U's actuated columns. */
  for (int j = 0; j < n; ++j)
    for (int which = 0; which < 2; ++which) {
      const double* src = (which ? lin->damping : lin->stiffness) + (size_t)j * n;
      for (int i = 0; i < n; ++i) col[i] = -src[i];
      f3r_cholesky_solve(L, n, col);
      for (int i = 0; i < n; ++i) F3R_AT(ss->A, nx, n + i, which * n + j) = col[i];
    }
  for (int u = 0; u < F3R_SS_INPUTS; ++u) {
    const int force = u < 3 ? F3R_FORCE_RHO + u : F3R_FORCE_THETA + (u - 3);
    memcpy(col, lin->input + (size_t)force * n, (size_t)n * sizeof(double));
    f3r_cholesky_solve(L, n, col);
    for (int i = 0; i < n; ++i) F3R_AT(ss->B, nx, n + i, u) = col[i];
  }
  double q0[F3R_MAX_Q] = {0};
  for (int k = 0; k < 3; ++k) q0[F3R_Q_X + k] = ss->x0[k] = model->scene.platform_pose0[k];
  if (f3r_model_close_loops(model, q0) != F3R_OK) { /* f3r_linearise has closed it already */
    st = f3r_error_set(err, F3R_ERR_SINGULAR, "state space: the initial pose cannot be reached");
    goto done;
  }
  outputs(model, q0, ss);
  name_everything(model, ss);
done:
  f3r_linear_destroy(lin);
  free(L);
  if (st == F3R_OK)
    *out = ss;
  else
    f3r_state_space_destroy(ss);
  return st;
}

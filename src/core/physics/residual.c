/* The public residual interface: workspace, state layouts and dispatch to a formulation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dense.h"
#include "workspace.h"

f3r_workspace* f3r_workspace_create(const f3r_model* m) {
  f3r_workspace* ws = calloc(1, sizeof *ws);
  if (!ws) return NULL;
  ws->nq = m->nq;
  ws->nz = m->n_independent;
  const int ny_dae = f3r_state_size(m, F3R_FORMULATION_DAE);
  ws->ny = ny_dae;
  ws->solve_work = calloc(f3r_solve_accelerations_work_size(m), sizeof(double));
  ws->y_perturbed = calloc((size_t)ny_dae, sizeof(double));
  ws->res_base = calloc((size_t)ny_dae, sizeof(double));
  ws->dQ = calloc(2 * (size_t)m->nq * (size_t)m->nq, sizeof(double));
  ws->stop_work = calloc(f3r_stop_forces_work_size(m), sizeof(double));
  const size_t nq = (size_t)m->nq, nz = (size_t)ws->nz;
  ws->jac_work = calloc(2 * nq * nq + 18 * nq + 3 * nq * nz + 6 * nz, sizeof(double));
  if (!ws->solve_work || !ws->y_perturbed || !ws->res_base || !ws->dQ || !ws->jac_work ||
      !ws->stop_work) {
    f3r_workspace_destroy(ws);
    return NULL;
  }
  return ws;
}

void f3r_workspace_destroy(f3r_workspace* ws) {
  if (!ws) return;
  free(ws->solve_work);
  free(ws->jac_work);
  free(ws->y_perturbed);
  free(ws->res_base);
  free(ws->dQ);
  free(ws->stop_work);
  free(ws);
}

long f3r_workspace_sincos_pairs(const f3r_workspace* ws) { return ws->data.sincos_pairs; }

/* The number of multipliers a redundant form carries after q and v: lambda and mu (dae),
 * lambda (index3), none (minimal). */
static int multipliers(f3r_formulation form) {
  return form == F3R_FORMULATION_DAE ? 2 * F3R_NCON : form == F3R_FORMULATION_INDEX3 ? F3R_NCON : 0;
}

int f3r_state_size(const f3r_model* m, f3r_formulation form) {
  return (form == F3R_FORMULATION_MINIMAL ? 2 * m->n_independent : 2 * m->nq + multipliers(form)) +
         m->n_lag + 1;
}

void f3r_state_kinds(const f3r_model* m, f3r_formulation form, double* id) {
  const int ny = f3r_state_size(m, form);
  for (int n = 0; n < ny; ++n) id[n] = 1.0;
  for (int c = 0; c < multipliers(form); ++c) id[2 * m->nq + c] = 0.0;
}

void f3r_index3_variable_indices(const f3r_model* m, int* index_of, int counts[3]) {
  const int nq = m->nq, ny = f3r_state_size(m, F3R_FORMULATION_INDEX3);
  for (int n = 0; n < ny; ++n) {
    const int k = n < nq ? 1 : n < 2 * nq ? 2 : n < 2 * nq + F3R_NCON ? 3 : 1; /* lag, W: 1 */
    if (index_of) index_of[n] = k;
  }
  if (counts) {
    counts[0] = nq + m->n_lag + 1;
    counts[1] = nq;
    counts[2] = F3R_NCON;
  }
}

/* x * 0.0 is a zero for a finite x and NaN for inf and NaN, so four sums of them are zeros unless
 * some x is not finite: four independent chains and no branch per entry (an isfinite test and
 * branch per entry was 5 % of a minimal residual at r = 3). */
static f3r_status check_finite(const double* x, int n) {
  double acc[4] = {0.0, 0.0, 0.0, 0.0};
  int i = 0;
  for (; i + 4 <= n; i += 4)
    for (int k = 0; k < 4; ++k) acc[k] += x[i + k] * 0.0;
  for (; i < n; ++i) acc[0] += x[i] * 0.0;
  return (acc[0] + acc[1]) + (acc[2] + acc[3]) == 0.0 ? F3R_OK : F3R_ERR_NONFINITE;
}

f3r_status f3r_residual(const f3r_model* m, f3r_formulation form, double t, const double* y,
                        const double* yp, const double* held, double* res, f3r_workspace* ws) {
  const f3r_status st = form == F3R_FORMULATION_MINIMAL
                            ? f3r_minimal_residual(m, t, y, yp, held, res, ws)
                            : f3r_dae_residual(m, form, t, y, yp, held, res, ws);
  if (st != F3R_OK) return st;
  return check_finite(res, f3r_state_size(m, form));
}

f3r_status f3r_stop_forces_at(const f3r_model* m, f3r_formulation form, double t, const double* y,
                              const double* held, double* f, f3r_workspace* ws) {
  double q[F3R_MAX_Q], v[F3R_MAX_Q], lag[3];
  f3r_status st = f3r_state_to_full(m, form, y, q, v);
  if (st != F3R_OK) return st;
  for (int i = 0; i < m->n_lag; ++i) lag[i] = y[f3r_lag_index(m, form) + i];
  f3r_data d = {.t = t, .q = q, .v = v, .held = held, .lag = m->n_lag ? lag : NULL};
  if ((st = f3r_forward(m, &d, F3R_FWD_POSITION | F3R_FWD_VELOCITY | F3R_FWD_FORCES)) != F3R_OK)
    return st;
  return f3r_stop_forces(m, &ws->locks, q, v, d.Q, f, ws->stop_work);
}

/* The residual's derivative through the stops' forces f(y), which the formulations take as
 * given forces: J += dF/df df/dy. dF/df is exact: F's dynamic rows hold -Q, so -e_i (dae) or
 * -B_i^T (minimal, B_i = d rho_i / dz), and the work row -v_i. df/dy is a central difference
 * quotient on the columns f depends on (q, v or z, u, and the lag states): 2 ny stop-force solves
 * per Jacobian, only while a leg is locked. */
static f3r_status add_stop_force_derivatives(const f3r_model* m, f3r_formulation form, double t,
                                             const double* y, const double* held, double* J, int ld,
                                             f3r_workspace* ws) {
  const int ny = f3r_state_size(m, form), minimal = form == F3R_FORMULATION_MINIMAL;
  const int n_pos = minimal ? m->n_independent : m->nq, lag_at = f3r_lag_index(m, form);
  double q[F3R_MAX_Q], v[F3R_MAX_Q], f0[3], f1[3];
  double dF_df[3][2 * F3R_MAX_Q + 16] = {{0.0}};
  f3r_status st = f3r_state_to_full(m, form, y, q, v);
  if (st != F3R_OK) return st;
  for (int i = 0; i < 3; ++i) {
    if (!ws->locks.side[i]) continue;
    dF_df[i][ny - 1] = -v[i];
    if (!minimal) {
      dF_df[i][m->nq + i] = -1.0;
      continue;
    }
    for (int j = 0; j < n_pos; ++j) { /* B_ij: the closure's rate of rho_i for u = e_j */
      double unit[F3R_MAX_Q] = {0.0};
      unit[F3R_Q_INDEPENDENT + j] = 1.0;
      f3r_model_close_loop_rates(m, q, unit);
      dF_df[i][n_pos + j] = -unit[i];
    }
  }
  double* yh = ws->y_perturbed;
  memcpy(yh, y, (size_t)ny * sizeof(double));
  for (int col = 0; col < ny; ++col) {
    const int is_lag = m->n_lag && col >= lag_at && col < lag_at + m->n_lag;
    if (col >= 2 * n_pos && !is_lag) continue; /* multipliers and W: f does not depend on them */
    const double h = 1e-6 * fmax(1e-2, fabs(y[col])); /* central: f is smooth */
    yh[col] = y[col] + h;
    st = f3r_stop_forces_at(m, form, t, yh, held, f1, ws);
    yh[col] = y[col] - h;
    if (st == F3R_OK) st = f3r_stop_forces_at(m, form, t, yh, held, f0, ws);
    yh[col] = y[col];
    if (st != F3R_OK) return st;
    for (int i = 0; i < 3; ++i) {
      if (!ws->locks.side[i]) continue;
      const double slope = (f1[i] - f0[i]) / (2.0 * h);
      for (int r = 0; r < ny; ++r) F3R_AT(J, ld, r, col) += dF_df[i][r] * slope;
    }
  }
  return F3R_OK;
}

f3r_status f3r_residual_jacobian(const f3r_model* m, f3r_formulation form, double t, double cj,
                                 const double* y, const double* yp, const double* held, double* J,
                                 int ld, f3r_workspace* ws) {
  const int ny = f3r_state_size(m, form);
  if (ld == ny) /* one call, not one a column */
    memset(J, 0, (size_t)ny * (size_t)ny * sizeof(double));
  else
    for (int j = 0; j < ny; ++j) memset(J + (size_t)j * (size_t)ld, 0, (size_t)ny * sizeof(double));
  const f3r_status st = form == F3R_FORMULATION_MINIMAL
                            ? f3r_minimal_jacobian(m, t, cj, y, yp, held, J, ld, ws)
                            : f3r_dae_jacobian(m, form, t, cj, y, yp, held, J, ld, ws);
  if (st != F3R_OK || !f3r_stop_locks_any(&ws->locks)) return st;
  return add_stop_force_derivatives(m, form, t, y, held, J, ld, ws);
}

f3r_status f3r_explicit_rhs(const f3r_model* m, double t, const double* y, const double* held,
                            double* ydot, f3r_workspace* ws) {
  const f3r_status st = f3r_minimal_rhs(m, t, y, held, ydot, ws);
  if (st != F3R_OK) return st;
  return check_finite(ydot, f3r_state_size(m, F3R_FORMULATION_MINIMAL));
}

f3r_status f3r_explicit_rhs_solver(const f3r_model* m, int structured, double t, const double* y,
                                   const double* held, double* ydot, f3r_workspace* ws) {
  const f3r_status st = structured ? f3r_minimal_rhs(m, t, y, held, ydot, ws)
                                   : f3r_minimal_rhs_dense(m, t, y, held, ydot, ws);
  if (st != F3R_OK) return st;
  return check_finite(ydot, f3r_state_size(m, F3R_FORMULATION_MINIMAL));
}

f3r_status f3r_state_to_full(const f3r_model* m, f3r_formulation form, const double* y, double* q,
                             double* v) {
  const int nq = m->nq, nz = m->n_independent;
  if (form != F3R_FORMULATION_MINIMAL) {
    memcpy(q, y, (size_t)nq * sizeof(double));
    memcpy(v, y + nq, (size_t)nq * sizeof(double));
    return F3R_OK;
  }
  memcpy(q + F3R_Q_INDEPENDENT, y, (size_t)nz * sizeof(double));
  memcpy(v + F3R_Q_INDEPENDENT, y + nz, (size_t)nz * sizeof(double));
  const f3r_status st = f3r_model_close_loops(m, q);
  if (st != F3R_OK) return st;
  f3r_model_close_loop_rates(m, q, v);
  return F3R_OK;
}

f3r_status f3r_consistent_state(const f3r_model* m, f3r_formulation form, double t, const double* q,
                                const double* v, const double* held, const double* lag, double work,
                                double* y, double* yp, double* lambda_out, f3r_workspace* ws) {
  const int nq = m->nq, nz = m->n_independent, ny = f3r_state_size(m, form);
  f3r_data* d = &ws->data;
  d->t = t;
  d->q = q;
  d->v = v;
  d->held = held;
  d->lag = lag;
  f3r_forward(m, d, F3R_FWD_POSITION | F3R_FWD_VELOCITY | F3R_FWD_FORCES);
  f3r_status st = f3r_workspace_add_stop_forces(m, ws, 0);
  if (st == F3R_OK) st = f3r_solve_accelerations(m, q, v, d->Q, d->a, d->lambda, ws->solve_work);
  if (st != F3R_OK) return st;
  if (lambda_out) memcpy(lambda_out, d->lambda, sizeof d->lambda);
  if (form != F3R_FORMULATION_MINIMAL) { /* mu = 0 (dae) */
    memset(y, 0, (size_t)ny * sizeof(double));
    memset(yp, 0, (size_t)ny * sizeof(double));
    memcpy(y, q, (size_t)nq * sizeof(double));
    memcpy(y + nq, v, (size_t)nq * sizeof(double));
    memcpy(y + 2 * nq, d->lambda, sizeof d->lambda);
    memcpy(yp, v, (size_t)nq * sizeof(double));
    memcpy(yp + nq, d->a, (size_t)nq * sizeof(double));
  } else {
    memcpy(y, q + F3R_Q_INDEPENDENT, (size_t)nz * sizeof(double));
    memcpy(y + nz, v + F3R_Q_INDEPENDENT, (size_t)nz * sizeof(double));
    memcpy(yp, v + F3R_Q_INDEPENDENT, (size_t)nz * sizeof(double));
    memcpy(yp + nz, d->a + F3R_Q_INDEPENDENT, (size_t)nz * sizeof(double));
  }
  for (int i = 0; i < m->n_lag; ++i) {
    const int k = f3r_lag_index(m, form) + i;
    y[k] = lag ? lag[i] : 0.0;
    yp[k] = (d->commanded[i] - y[k]) / m->lag_time_constant;
  }
  y[ny - 1] = work;
  yp[ny - 1] = d->power;
  return check_finite(y, f3r_state_size(m, form));
}

void f3r_workspace_set_locks(f3r_workspace* ws, const int side[3]) {
  for (int i = 0; i < 3; ++i) ws->locks.side[i] = side[i];
}

/* The redundant-coordinate residuals and their exact Jacobians, in named blocks read from one
 * forward pass (data.h): the stabilised index-2 (Gear-Gupta-Leimkuhler) form `dae` and the plain
 * index-3 form `index3` (no mu, no velocity constraint) that the paper's MEBDFI integrates.
 * Layouts and equations: residual.h. */
#include "dense.h"
#include "derivatives.h"
#include "effects.h"
#include "form_dae.h"

void f3r_dae_rows(const f3r_model* m, f3r_formulation form, const double* y, const double* yp,
                  const f3r_data* d, double* res) {
  const int nq = m->nq, ggl = form == F3R_FORMULATION_DAE;
  const double *v = y + nq, *qd = yp;
  const int lag_at = m->lag_index[form], w_at = lag_at + m->n_lag;

  /* kinematic rows: q' - v (+ G^T mu) */
  for (int n = 0; n < nq; ++n) res[n] = qd[n] - v[n];
  if (ggl)
    for (int n = 0; n < nq; ++n) res[n] += d->gt_mu[n];

  /* dynamic rows: M v' + h + k - Q - G^T lambda, the acceleration stage's R */
  for (int n = 0; n < nq; ++n) res[nq + n] = d->R[n];

  /* position (and velocity) constraints: g(q) (, G v) */
  for (int c = 0; c < F3R_NCON; ++c) res[2 * nq + c] = d->g[c];
  if (ggl)
    for (int c = 0; c < F3R_NCON; ++c) res[2 * nq + F3R_NCON + c] = d->gv[c];

  /* actuator lag and work */
  for (int i = 0; i < m->n_lag; ++i)
    res[lag_at + i] = m->lag_time_constant * yp[lag_at + i] - (d->commanded[i] - y[lag_at + i]);
  res[w_at] = yp[w_at] - d->power;
}

void f3r_dae_jacobian(const f3r_model* m, f3r_formulation form, double cj, const double* y,
                      const double* yp, double* J, int ld, f3r_workspace* ws) {
  const int nq = m->nq, ggl = form == F3R_FORMULATION_DAE;
  const int row_v = nq, row_g = 2 * nq, row_gv = 2 * nq + F3R_NCON;
  const int row_lag = m->lag_index[form], row_w = row_lag + m->n_lag;
  const int col_v = nq, col_lambda = 2 * nq, col_mu = 2 * nq + F3R_NCON, col_w = row_w;
  const double *q = y, *v = y + nq, *lambda = y + 2 * nq, *mu = lambda + F3R_NCON;
  const double* vd = yp + nq;
  const f3r_data* d = &ws->data;
#define BLOCK(row, col) (J + (size_t)(col) * (size_t)ld + (row))

  /* q' - v (+ G^T mu) */
  for (int n = 0; n < nq; ++n) {
    F3R_AT(J, ld, n, n) += cj;
    F3R_AT(J, ld, n, col_v + n) -= 1.0;
  }
  if (ggl) {
    f3r_data_add_constraint_transpose_times_dq(m, d, mu, 1.0, BLOCK(0, 0), ld);
    f3r_data_add_constraint_jacobian_transpose(m, d, 1.0, BLOCK(0, col_mu), ld);
  }

  /* M v' + h + k - Q - G^T lambda */
  f3r_add_mass_times_dq(m, q, vd, 1.0, BLOCK(row_v, 0), ld);
  f3r_add_velocity_forces_dq(m, q, v, 1.0, BLOCK(row_v, 0), ld);
  f3r_add_elastic_forces_dq(m, 1.0, BLOCK(row_v, 0), ld);
  f3r_data_add_constraint_transpose_times_dq(m, d, lambda, -1.0, BLOCK(row_v, 0), ld);
  f3r_data_add_mass_matrix(m, d, cj, BLOCK(row_v, col_v), ld);
  f3r_data_add_velocity_forces_dv(m, d, q, 1.0, BLOCK(row_v, col_v), ld);
  f3r_data_add_constraint_jacobian_transpose(m, d, -1.0, BLOCK(row_v, col_lambda), ld);

  /* g(q) (and G v) */
  f3r_data_add_constraint_jacobian(m, d, 1.0, BLOCK(row_g, 0), ld);
  if (ggl) {
    f3r_data_add_constraint_times_dq(m, d, v, 1.0, BLOCK(row_gv, 0), ld);
    f3r_data_add_constraint_jacobian(m, d, 1.0, BLOCK(row_gv, col_v), ld);
  }

  /* -dQ/dq, -dQ/dv of the effects; W' - Q . v: d/dv = -Q - (dQ/dv)^T v, d/dq = -(dQ/dq)^T v */
  for (int n = 0; n < nq; ++n) F3R_AT(J, ld, row_w, col_v + n) -= d->Q[n];
  /* actuator lag: tau F_a' - (F_cmd - F_a); the applied F_a enters Q_rho and Q . v */
  for (int i = 0; i < m->n_lag; ++i) {
    F3R_AT(J, ld, row_lag + i, row_lag + i) += 1.0 + cj * m->lag_time_constant;
    F3R_AT(J, ld, row_v + i, row_lag + i) -= 1.0;
    F3R_AT(J, ld, row_w, row_lag + i) -= v[i];
  }
  if (f3r_effects_have_derivatives(m)) {
    double* dq = ws->dQ;
    double* dv = ws->dQ + (size_t)nq * (size_t)nq;
    for (size_t z = 0; z < 2 * (size_t)nq * (size_t)nq; ++z) ws->dQ[z] = 0.0;
    f3r_effects_add_derivatives(m, d, 1.0, dq, dv, nq);
    for (int j = 0; j < nq; ++j) {
      double wq = 0.0, wv = 0.0;
      for (int i = 0; i < nq; ++i) {
        F3R_AT(J, ld, row_v + i, j) -= F3R_AT(dq, nq, i, j);
        F3R_AT(J, ld, row_v + i, col_v + j) -= F3R_AT(dv, nq, i, j);
        wq += F3R_AT(dq, nq, i, j) * v[i];
        wv += F3R_AT(dv, nq, i, j) * v[i];
      }
      F3R_AT(J, ld, row_w, j) -= wq;
      F3R_AT(J, ld, row_w, col_v + j) -= wv;
    }
  }
  F3R_AT(J, ld, row_w, col_w) += cj;
#undef BLOCK
}

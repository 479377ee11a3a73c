/* The minimal-coordinate residual: independent z = (X_p, Y_p, phi_p, eta), with rho and theta
 * from the closed-form loop closure. Layout and equations: include/flex3rpr/residual.h.
 *
 * Per link, the dependent block of G is G_d = [e, L n - w e], det = L = rho + l, so
 *   G_d x = V     gives  theta = (n.V)/L,  rho = e.V + w theta,
 *   G_d^T x = R   gives  x = R_rho e + ((R_theta + w R_rho)/L) n.
 * Accelerations: a_d = G_d^{-1} (-G_z a_z - gamma). The reduced equations B^T R = 0 are
 * R_z - G_z^T lambda with lambda = G_d^{-T} R_d, which is also the constraint force. */
#include <math.h>
#include <string.h>

#include "dense.h"
#include "workspace.h"

static void dependent_accelerations(const f3r_model* m, f3r_data* d);

/* The position and velocity stages from the minimal state, then the full accelerations: the
 * loop closure fills rho, rho', theta' (not theta: nothing in the residual needs the angle
 * itself), and a_d = G_d^{-1} (-G_z a_z - gamma). */
static f3r_status expand(const f3r_model* m, const double* y, const double* yp,
                         f3r_workspace* ws) {
  const int nz = m->n_independent;
  f3r_data* d = &ws->data;
  double *q = ws->q, *v = ws->v;
  memcpy(q + F3R_Q_INDEPENDENT, y, (size_t)nz * sizeof(double));
  memcpy(v + F3R_Q_INDEPENDENT, y + nz, (size_t)nz * sizeof(double));
  const f3r_status st = f3r_fwd_position_closed(m, q, d);
  if (st != F3R_OK) return st;
  f3r_fwd_velocity_closed(m, q, v, d);
  memcpy(d->a + F3R_Q_INDEPENDENT, yp + nz, (size_t)nz * sizeof(double));
  dependent_accelerations(m, d);
  return F3R_OK;
}

/* The dependent accelerations a_d = G_d^{-1} (-G_z a_z - gamma), with a_z given in d->a. */
static void dependent_accelerations(const f3r_model* m, f3r_data* d) {
  double* a = d->a;
  for (int n = 0; n < F3R_Q_INDEPENDENT; ++n) a[n] = 0.0;
  double rhs[F3R_NCON];
  f3r_data_constraint_times(m, d, a, rhs); /* G_z a_z */
  for (int c = 0; c < F3R_NCON; ++c) rhs[c] = -rhs[c] - d->gamma[c];
  f3r_data_solve_dependent(d, rhs, a);
}

/* R = M a + h + k - Q; its dependent rows give the loop forces lambda = G_d^{-T} R_d, its
 * independent rows less G_z^T lambda are the reduced equations B^T R. */
static void loop_forces(const f3r_model* m, f3r_data* d) {
  double* R = d->R;
  f3r_data_mass_times(m, d, d->a, R);
  for (int n = 0; n < m->nq; ++n) R[n] += d->h[n] + d->k[n] - d->Q[n];
  f3r_data_solve_dependent_transpose(d, R, d->lambda);
}

void f3r_minimal_multipliers(const f3r_model* m, const double* yp, f3r_data* d) {
  memcpy(d->a + F3R_Q_INDEPENDENT, yp + m->n_independent, (size_t)m->n_independent * sizeof(double));
  dependent_accelerations(m, d);
  loop_forces(m, d);
}

f3r_status f3r_minimal_residual(const f3r_model* m, double t, const double* y, const double* yp,
                                const double* held, double* res, f3r_workspace* ws) {
  const int nz = m->n_independent;
  const f3r_status st = expand(m, y, yp, ws);
  if (st != F3R_OK) return st;
  f3r_data* d = &ws->data;
  const int lag_at = f3r_lag_index(m, F3R_FORMULATION_MINIMAL), w_at = lag_at + m->n_lag;
  f3r_fwd_forces(m, t, held, ws->q, ws->v, m->n_lag ? y + lag_at : 0, d);
  loop_forces(m, d);
  const double* R = d->R;
  f3r_data_constraint_transpose_times(m, d, d->lambda, ws->tmp);
  for (int j = 0; j < nz; ++j) {
    res[j] = yp[j] - y[nz + j];
    res[nz + j] = R[F3R_Q_INDEPENDENT + j] - ws->tmp[F3R_Q_INDEPENDENT + j];
  }
  for (int i = 0; i < m->n_lag; ++i)
    res[lag_at + i] = m->lag_time_constant * yp[lag_at + i] - (d->commanded[i] - y[lag_at + i]);
  res[w_at] = yp[w_at] - d->power;
  return F3R_OK;
}

/* Typical magnitudes that set the difference increments: m for the pose, m for modal
 * coordinates, and their rates. */
static double typical_size(const f3r_model* m, int index) {
  const int nz = m->n_independent;
  const int j = index % nz;
  const int is_rate = index >= nz;
  if (j < 3) return is_rate ? 1e-1 : 1e-1;
  return is_rate ? 1e-2 : 1e-5;
}

/* B (nq x nz) and M B at the position stage in ws->data (the last expanded state). B is the
 * identity on z above the dependent rows G_d^{-1} (-G_z). */
static void assemble_velocity_map(const f3r_model* m, f3r_workspace* ws) {
  const int nq = m->nq, nz = m->n_independent;
  const f3r_data* d = &ws->data;
  double *B = ws->B, *M = ws->M, *G = ws->G;
  memset(B, 0, (size_t)nq * (size_t)nz * sizeof(double));
  memset(M, 0, (size_t)nq * (size_t)nq * sizeof(double));
  memset(G, 0, (size_t)F3R_NCON * (size_t)nq * sizeof(double));
  f3r_data_add_mass_matrix(m, d, 1.0, M, nq);
  f3r_data_add_constraint_jacobian(m, d, 1.0, G, F3R_NCON);
  for (int j = 0; j < nz; ++j) {
    double* col = B + (size_t)j * (size_t)nq;
    double V[F3R_NCON];
    for (int c = 0; c < F3R_NCON; ++c) V[c] = -F3R_AT(G, F3R_NCON, c, F3R_Q_INDEPENDENT + j);
    col[F3R_Q_INDEPENDENT + j] = 1.0;
    f3r_data_solve_dependent(d, V, col);
    /* M B: B's column is nonzero only in the legs' rows and in row F3R_Q_INDEPENDENT + j */
    double* out = ws->MB + (size_t)j * (size_t)nq;
    for (int n = 0; n < nq; ++n) {
      double sum = F3R_AT(M, nq, n, F3R_Q_INDEPENDENT + j);
      for (int d = 0; d < F3R_Q_LEG_JOINTS; ++d) sum += F3R_AT(M, nq, n, d) * col[d];
      out[n] = sum;
    }
  }
}

/* (B^T M B)(i, j): column i of B is nonzero only in the legs' (dependent) rows and in row
 * F3R_Q_INDEPENDENT + i. */
static double reduced_mass(const f3r_model* m, const f3r_workspace* ws, int i, int j) {
  const int nq = m->nq;
  const double *b = ws->B + (size_t)i * nq, *mb = ws->MB + (size_t)j * nq;
  double s = mb[F3R_Q_INDEPENDENT + i];
  for (int d = 0; d < F3R_Q_LEG_JOINTS; ++d) s += b[d] * mb[d];
  return s;
}

f3r_status f3r_minimal_rhs(const f3r_model* m, double t, const double* y, const double* held,
                           double* ydot, f3r_workspace* ws) {
  const int nz = m->n_independent, ny = f3r_state_size(m, F3R_FORMULATION_MINIMAL);
  /* F_u is linear in u': F_u(u') = F_u(0) + B^T M B u'; likewise the lag and W rows. */
  double* zero_rate = ws->y_perturbed;
  memset(zero_rate, 0, (size_t)ny * sizeof(double));
  f3r_status st = f3r_minimal_residual(m, t, y, zero_rate, held, ws->res_base, ws);
  if (st != F3R_OK) return st;
  assemble_velocity_map(m, ws);
  double* K = ws->solve_work; /* nz x nz fits in the (nq + 6)^2 of the acceleration solver */
  for (int j = 0; j < nz; ++j)
    for (int i = j; i < nz; ++i) F3R_AT(K, nz, i, j) = reduced_mass(m, ws, i, j);
  double* rate = ydot + nz;
  for (int i = 0; i < nz; ++i) rate[i] = -ws->res_base[nz + i];
  if (f3r_cholesky_factor(K, nz)) return F3R_ERR_SINGULAR; /* B^T M B is positive definite */
  f3r_cholesky_solve(K, nz, rate);
  for (int i = 0; i < nz; ++i) ydot[i] = y[nz + i];
  const int lag_at = 2 * nz;
  for (int i = 0; i < m->n_lag; ++i) ydot[lag_at + i] = -ws->res_base[lag_at + i] / m->lag_time_constant;
  ydot[ny - 1] = -ws->res_base[ny - 1]; /* F_W(W' = 0) = -Q.v */
  return F3R_OK;
}

f3r_status f3r_minimal_jacobian(const f3r_model* m, double t, double cj, const double* y,
                                const double* yp, const double* held, double* J, int ld,
                                f3r_workspace* ws) {
  const int nz = m->n_independent, ny = f3r_state_size(m, F3R_FORMULATION_MINIMAL);
  f3r_status st = f3r_minimal_residual(m, t, y, yp, held, ws->res_base, ws);
  if (st != F3R_OK) return st;
  memcpy(ws->y_perturbed, y, (size_t)ny * sizeof(double));
  for (int j = 0; j < ny - 1; ++j) { /* every column but W's, which nothing depends on */
    const double inc = 1.5e-8 * fmax(fabs(y[j]), j < 2 * nz ? typical_size(m, j) : 1.0);
    ws->y_perturbed[j] = y[j] + inc;
    st = f3r_minimal_residual(m, t, ws->y_perturbed, yp, held, ws->res_perturbed, ws);
    ws->y_perturbed[j] = y[j];
    if (st != F3R_OK) return st;
    for (int i = 0; i < ny; ++i)
      F3R_AT(J, ld, i, j) += (ws->res_perturbed[i] - ws->res_base[i]) / inc;
  }
  /* cj dF/dy': identity for z and W, B^T M B for u, tau for the lag states. */
  for (int j = 0; j < nz; ++j) F3R_AT(J, ld, j, j) += cj;
  for (int i = 0; i < m->n_lag; ++i) F3R_AT(J, ld, 2 * nz + i, 2 * nz + i) += cj * m->lag_time_constant;
  F3R_AT(J, ld, ny - 1, ny - 1) += cj;
  st = expand(m, y, yp, ws); /* restores the position stage at y */
  if (st != F3R_OK) return st;
  assemble_velocity_map(m, ws);
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nz; ++i) F3R_AT(J, ld, nz + i, nz + j) += cj * reduced_mass(m, ws, i, j);
  return F3R_OK;
}

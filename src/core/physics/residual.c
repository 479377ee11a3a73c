/* The residual interface: dispatch to a formulation, the end stops' share of the Jacobian, the
 * state layouts' kinds and consistent states. The formulations never call back here. */
#include <math.h>
#include <string.h>

#include "dense.h"
#include "form_dae.h"
#include "form_minimal.h"
#include "forward.h"
#include "queries.h"
#include "residual.h"

void f3r_state_kinds(const f3r_model* m, f3r_formulation form, double* id) {
  const int ny = m->state_size[form];
  /* the multipliers of a redundant form, between v and the lag states */
  const int multipliers = form == F3R_FORMULATION_MINIMAL ? 0 : m->lag_index[form] - 2 * m->nq;
  for (int n = 0; n < ny; ++n) id[n] = 1.0;
  for (int c = 0; c < multipliers; ++c) id[2 * m->nq + c] = 0.0;
}

void f3r_index3_variable_indices(const f3r_model* m, int* index_of, int counts[3]) {
  const int nq = m->nq, ny = m->state_size[F3R_FORMULATION_INDEX3];
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

/* The forward pass's inputs from a formulation's state y (residual.h's layouts) and its rate yp
 * (NULL: no acceleration stage), and the stages its residual needs through the end stops' forces
 * and, with yp, the acceleration stage. */
static unsigned bind_state(const f3r_model* m, f3r_formulation form, double t, const double* y,
                           const double* yp, const double* held, f3r_workspace* ws, f3r_data* d) {
  d->t = t;
  d->held = held;
  d->lag = m->n_lag ? y + m->lag_index[form] : NULL;
  d->locks = &ws->locks;
  d->stop_work = ws->stop_work;
  if (form == F3R_FORMULATION_MINIMAL) {
    const int nz = m->n_independent;
    d->z = y, d->u = y + nz, d->udot = yp ? yp + nz : NULL, d->reduced = NULL;
    return F3R_FWD_POSITION_CLOSED | F3R_FWD_VELOCITY_CLOSED | F3R_FWD_FORCES | F3R_FWD_STOPS |
           (yp ? F3R_FWD_ACCELERATION_CLOSED : 0);
  }
  const int nq = m->nq;
  d->q = y, d->v = y + nq, d->vdot = yp ? yp + nq : NULL;
  d->multipliers = y + 2 * nq, d->mu = form == F3R_FORMULATION_DAE ? y + 2 * nq + F3R_NCON : NULL;
  return F3R_FWD_POSITION | F3R_FWD_VELOCITY | F3R_FWD_FORCES | F3R_FWD_STOPS |
         (yp ? F3R_FWD_ACCELERATION : 0);
}

f3r_status f3r_residual(const f3r_model* m, f3r_formulation form, double t, const double* y,
                        const double* yp, const double* held, double* res, f3r_workspace* ws) {
  f3r_data* d = &ws->data;
  const unsigned what = bind_state(m, form, t, y, yp, held, ws, d);
  if (form == F3R_FORMULATION_MINIMAL) d->reduced = res + m->n_independent; /* the rows' place */
  const f3r_status st = f3r_forward(m, d, what);
  if (st != F3R_OK) return st;
  if (form == F3R_FORMULATION_MINIMAL)
    f3r_minimal_rows(m, y, yp, d, res);
  else
    f3r_dae_rows(m, form, y, yp, d, res);
  return check_finite(res, m->state_size[form]);
}

f3r_status f3r_stop_forces_at(const f3r_model* m, f3r_formulation form, double t, const double* y,
                              const double* held, double* f, f3r_workspace* ws) {
  f3r_data d = {.t = t}; /* the formulation's own pass, as its residual runs it */
  const unsigned what = bind_state(m, form, t, y, NULL, held, ws, &d);
  const f3r_status st = f3r_forward(m, &d, what);
  if (st != F3R_OK) return st;
  memcpy(f, d.stop_force, sizeof d.stop_force);
  return F3R_OK;
}

/* The residual's derivative through the stops' forces f(y), which the formulations take as
 * given forces: J += dF/df df/dy. dF/df is exact: F's dynamic rows hold -Q, so -e_i (dae) or
 * -B_i^T (minimal, B_i = d rho_i / dz), and the work row -v_i. df/dy is a central difference
 * quotient on the columns f depends on (q, v or z, u, and the lag states): 2 ny stop-force solves
 * per Jacobian, only while a leg is locked. */
static f3r_status add_stop_force_derivatives(const f3r_model* m, f3r_formulation form, double t,
                                             const double* y, const double* held, double* J, int ld,
                                             f3r_workspace* ws) {
  const int ny = m->state_size[form], minimal = form == F3R_FORMULATION_MINIMAL;
  const int n_pos = minimal ? m->n_independent : m->nq, lag_at = m->lag_index[form];
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
  const int ny = m->state_size[form], minimal = form == F3R_FORMULATION_MINIMAL;
  if (ld == ny) /* one call, not one a column */
    memset(J, 0, (size_t)ny * (size_t)ny * sizeof(double));
  else
    for (int j = 0; j < ny; ++j) memset(J + (size_t)j * (size_t)ld, 0, (size_t)ny * sizeof(double));
  f3r_data* d = &ws->data;
  /* the dae Jacobian reads no acceleration stage; the minimal one its a, R and lambda */
  const unsigned what = bind_state(m, form, t, y, minimal ? yp : NULL, held, ws, d);
  const f3r_status st = f3r_forward(m, d, what);
  if (st != F3R_OK) return st;
  if (minimal)
    f3r_minimal_jacobian(m, cj, J, ld, ws);
  else
    f3r_dae_jacobian(m, form, cj, y, yp, J, ld, ws);
  if (!f3r_stop_locks_any(&ws->locks)) return F3R_OK;
  return add_stop_force_derivatives(m, form, t, y, held, J, ld, ws);
}

f3r_status f3r_explicit_rhs(const f3r_model* m, double t, const double* y, const double* held,
                            double* ydot, f3r_workspace* ws) {
  return f3r_explicit_rhs_solver(m, 1, t, y, held, ydot, ws);
}

f3r_status f3r_explicit_rhs_solver(const f3r_model* m, int structured, double t, const double* y,
                                   const double* held, double* ydot, f3r_workspace* ws) {
  const f3r_formulation form = F3R_FORMULATION_MINIMAL;
  f3r_data* d = &ws->data;
  const unsigned what = bind_state(m, form, t, y, NULL, held, ws, d); /* u' = 0: F_u(0) */
  d->reduced = ydot + m->n_independent;
  f3r_status st = f3r_forward(m, d, what | F3R_FWD_ACCELERATION_CLOSED);
  if (st == F3R_OK) st = f3r_minimal_rhs(m, structured, y, ydot, ws);
  if (st != F3R_OK) return st;
  return check_finite(ydot, m->state_size[form]);
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
  const int nq = m->nq, nz = m->n_independent, ny = m->state_size[form];
  f3r_data* d = &ws->data;
  d->t = t;
  d->q = q;
  d->v = v;
  d->held = held;
  d->lag = lag;
  d->locks = &ws->locks;
  d->stop_work = ws->stop_work;
  f3r_status st =
      f3r_forward(m, d, F3R_FWD_POSITION | F3R_FWD_VELOCITY | F3R_FWD_FORCES | F3R_FWD_STOPS);
  if (st == F3R_OK) st = f3r_data_solve_accelerations(m, d, d->Q, d->a, d->lambda, ws->solve_work);
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
    const int k = m->lag_index[form] + i;
    y[k] = lag ? lag[i] : 0.0;
    yp[k] = (d->commanded[i] - y[k]) / m->lag_time_constant;
  }
  y[ny - 1] = work;
  yp[ny - 1] = d->power;
  return check_finite(y, ny);
}

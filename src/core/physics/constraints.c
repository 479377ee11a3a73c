/* Loop-closure constraints (paper eqs. 13-17) and their derivatives.
 *
 * With e = (cos th, sin th), n = (-sin th, cos th), L = rho + l, w = w_i(l) the tip deflection
 * (0 for rigid and fixed-pinned links, whose modes vanish at the tip), and C_i on the platform at
 * P + r_PC e_c, e_c = (cos(phi_i + phi_p), sin(phi_i + phi_p)), n_c its normal:
 *   g_i = A_i + L e + w n - P - r_PC e_c                                  (2 rows per link)
 *   G_i: d/drho = e, d/dth = L n - w e, d/deta_j = psi_j(1) n, d/dP = -I, d/dphi_p = -r_PC n_c
 *   gamma_i = (dG_i/dt) v = 2 rho' th' n - L th'^2 e - 2 w' th' e - w th'^2 n + r_PC phi'^2 e_c */
#include <math.h>
#include <string.h>

#include "data.h"
#include "dense.h"

/* --- the stages' per-link parts (forward.c) ------------------------------------------------- */

void f3r_link_constraints(const f3r_model* m, int i, f3r_data* d, int closed) {
  f3r_link_data* k = &d->link[i];
  const double r = m->platform_radius;
  k->g_theta[0] = -k->len * k->s - k->w * k->c;
  k->g_theta[1] = k->len * k->c - k->w * k->s;
  k->g_phi[0] = r * k->sc;
  k->g_phi[1] = -r * k->cc;
  if (closed) {
    d->g[2 * i] = d->g[2 * i + 1] = 0.0;
    return;
  }
  const double* q = d->q;
  d->g[2 * i] = m->base_joint[i][0] + k->len * k->c - k->w * k->s - q[F3R_Q_X] - r * k->cc;
  d->g[2 * i + 1] = m->base_joint[i][1] + k->len * k->s + k->w * k->c - q[F3R_Q_Y] - r * k->sc;
}

/* gamma_i = along e + across n + r_PC phi'^2 e_c (the header's comment). */
void f3r_link_constraint_bias(const f3r_model* m, int i, f3r_data* d) {
  const f3r_link_data* k = &d->link[i];
  const double td = k->theta_dot, phi_dot = d->v[F3R_Q_PHI];
  const double along = -k->len * td * td - 2.0 * k->w_dot * td; /* e component */
  const double across = 2.0 * k->rho_dot * td - k->w * td * td; /* n component */
  const double rp = m->platform_radius * phi_dot * phi_dot;
  d->gamma[2 * i] = along * k->c - across * k->s + rp * k->cc;
  d->gamma[2 * i + 1] = along * k->s + across * k->c + rp * k->sc;
}

/* --- kernels on the position stage ---------------------------------------------------------- */

/* Calls put(row, col, value) for every nonzero of G, so G and G^T share one definition. */
#define F3R_FOR_EACH_G_ENTRY(m, d, PUT)                  \
  for (int i = 0; i < 3; ++i) {                          \
    const f3r_link_data* k = &(d)->link[i];              \
    const int gx = 2 * i, gy = 2 * i + 1;                \
    PUT(gx, i, k->c);                                    \
    PUT(gy, i, k->s);                                    \
    PUT(gx, F3R_Q_THETA + i, k->g_theta[0]);             \
    PUT(gy, F3R_Q_THETA + i, k->g_theta[1]);             \
    PUT(gx, F3R_Q_X, -1.0);                              \
    PUT(gy, F3R_Q_Y, -1.0);                              \
    PUT(gx, F3R_Q_PHI, k->g_phi[0]);                     \
    PUT(gy, F3R_Q_PHI, k->g_phi[1]);                     \
    const f3r_link_params* lp = &(m)->link[i];           \
    if (lp->model == F3R_LINK_FIXED_FREE)                \
      for (int j = 0; j < lp->modes; ++j) {              \
        double g_x, g_y;                                 \
        f3r_link_modal_constraint(lp, k, j, &g_x, &g_y); \
        PUT(gx, lp->eta_index + j, g_x);                 \
        PUT(gy, lp->eta_index + j, g_y);                 \
      }                                                  \
  }

void f3r_data_add_constraint_jacobian(const f3r_model* m, const f3r_data* d, double scale,
                                      double* A, int ld) {
#define PUT_G(row, col, value) F3R_AT(A, ld, row, col) += scale * (value)
  F3R_FOR_EACH_G_ENTRY(m, d, PUT_G)
#undef PUT_G
}

void f3r_data_add_constraint_jacobian_transpose(const f3r_model* m, const f3r_data* d, double scale,
                                                double* A, int ld) {
#define PUT_GT(row, col, value) F3R_AT(A, ld, col, row) += scale * (value)
  F3R_FOR_EACH_G_ENTRY(m, d, PUT_GT)
#undef PUT_GT
}

void f3r_data_constraint_times(const f3r_model* m, const f3r_data* d, const double* x,
                               double* out) {
  for (int c = 0; c < F3R_NCON; ++c) out[c] = 0.0;
#define PUT_GV(row, col, value) out[row] += (value)*x[col]
  F3R_FOR_EACH_G_ENTRY(m, d, PUT_GV)
#undef PUT_GV
}

void f3r_data_constraint_transpose_times(const f3r_model* m, const f3r_data* d, const double* y,
                                         double* out) {
  for (int n = 0; n < m->nq; ++n) out[n] = 0.0;
#define PUT_GTL(row, col, value) out[col] += (value)*y[row]
  F3R_FOR_EACH_G_ENTRY(m, d, PUT_GTL)
#undef PUT_GTL
}

/* Second derivatives of g: for a 6-vector y, d(G^T y)/dq and, with the same terms transposed,
 * d(G v)/dq. Nonzero only in the (rho, theta, eta) block of each link and at (phi_p, phi_p). */
void f3r_data_add_constraint_transpose_times_dq(const f3r_model* m, const f3r_data* d,
                                                const double* y, double scale, double* A, int ld) {
  double phi_phi = 0.0;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const double lx = y[2 * i], ly = y[2 * i + 1];
    const double e_l = k->c * lx + k->s * ly, n_l = -k->s * lx + k->c * ly;
    const int r = i, t = F3R_Q_THETA + i;
    F3R_AT(A, ld, r, t) += scale * n_l;
    F3R_AT(A, ld, t, r) += scale * n_l;
    F3R_AT(A, ld, t, t) += scale * (-k->len * e_l - k->w * n_l);
    const f3r_link_params* lp = &m->link[i];
    if (lp->model == F3R_LINK_FIXED_FREE)
      for (int j = 0; j < lp->modes; ++j) {
        const int col = lp->eta_index + j;
        F3R_AT(A, ld, t, col) += scale * (-lp->tip[j] * e_l);
        F3R_AT(A, ld, col, t) += scale * (-lp->tip[j] * e_l);
      }
    phi_phi += m->platform_radius * (k->cc * lx + k->sc * ly);
  }
  F3R_AT(A, ld, F3R_Q_PHI, F3R_Q_PHI) += scale * phi_phi;
}

/* d(G x)/dq for any x (v, or the accelerations a). */
void f3r_data_add_constraint_times_dq(const f3r_model* m, const f3r_data* d, const double* x,
                                      double scale, double* A, int ld) {
  const double* v = x;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const f3r_link_params* lp = &m->link[i];
    const int gx = 2 * i, gy = 2 * i + 1, r = i, t = F3R_Q_THETA + i;
    const double rd = x[F3R_Q_RHO + i], td = x[F3R_Q_THETA + i];
    double wd = 0.0;
    for (int j = 0; j < lp->modes; ++j) wd += lp->tip[j] * x[lp->eta_index + j];
    /* d/drho = n th' */
    F3R_AT(A, ld, gx, r) += scale * (-k->s * td);
    F3R_AT(A, ld, gy, r) += scale * (k->c * td);
    /* d/dth = n rho' - (L e + w n) th' - w' e */
    F3R_AT(A, ld, gx, t) += scale * (-k->s * rd - (k->len * k->c - k->w * k->s) * td - wd * k->c);
    F3R_AT(A, ld, gy, t) += scale * (k->c * rd - (k->len * k->s + k->w * k->c) * td - wd * k->s);
    if (lp->model == F3R_LINK_FIXED_FREE)
      for (int j = 0; j < lp->modes; ++j) { /* d/deta_j = -psi_j(1) e th' */
        const int col = lp->eta_index + j;
        F3R_AT(A, ld, gx, col) += scale * (-lp->tip[j] * k->c * td);
        F3R_AT(A, ld, gy, col) += scale * (-lp->tip[j] * k->s * td);
      }
    /* d/dphi_p = r_PC e_c phi' */
    F3R_AT(A, ld, gx, F3R_Q_PHI) += scale * (m->platform_radius * k->cc * v[F3R_Q_PHI]);
    F3R_AT(A, ld, gy, F3R_Q_PHI) += scale * (m->platform_radius * k->sc * v[F3R_Q_PHI]);
  }
}

/* gamma_i = along e + across n + r_PC phi'^2 e_c with along = -L th'^2 - 2 w' th' and
 * across = 2 rho' th' - w th'^2 (f3r_link_constraint_bias), so, per link,
 *   d/drho = -th'^2 e,  d/dth = along n - across e,  d/deta_j = -psi_j(1) th'^2 n,
 *   d/dphi_p = r_PC phi'^2 (-sc, cc);
 *   d/drho' = 2 th' n,  d/dth' = (-2 L th' - 2 w') e + (2 rho' - 2 w th') n,
 *   d/deta_j' = -2 psi_j(1) th' e,  d/dphi_p' = 2 r_PC phi' e_c.
 * Both need the velocity stage of v in d. */
void f3r_data_add_constraint_bias_dq(const f3r_model* m, const f3r_data* d, const double* v,
                                     double scale, double* A, int ld) {
  const double pd = v[F3R_Q_PHI], rp = m->platform_radius * pd * pd;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const f3r_link_params* lp = &m->link[i];
    const int gx = 2 * i, gy = 2 * i + 1;
    const double rd = k->rho_dot, td = k->theta_dot;
    const double along = -k->len * td * td - 2.0 * k->w_dot * td,
                 across = 2.0 * rd * td - k->w * td * td;
    F3R_AT(A, ld, gx, F3R_Q_RHO + i) += scale * (-td * td * k->c);
    F3R_AT(A, ld, gy, F3R_Q_RHO + i) += scale * (-td * td * k->s);
    F3R_AT(A, ld, gx, F3R_Q_THETA + i) += scale * (-along * k->s - across * k->c);
    F3R_AT(A, ld, gy, F3R_Q_THETA + i) += scale * (along * k->c - across * k->s);
    for (int j = 0; j < lp->modes; ++j) {
      const int col = lp->eta_index + j;
      F3R_AT(A, ld, gx, col) += scale * (lp->tip[j] * td * td * k->s);
      F3R_AT(A, ld, gy, col) += scale * (-lp->tip[j] * td * td * k->c);
    }
    F3R_AT(A, ld, gx, F3R_Q_PHI) += scale * (-rp * k->sc);
    F3R_AT(A, ld, gy, F3R_Q_PHI) += scale * (rp * k->cc);
  }
}

void f3r_data_add_constraint_bias_dv(const f3r_model* m, const f3r_data* d, const double* v,
                                     double scale, double* A, int ld) {
  const double pd = v[F3R_Q_PHI];
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const f3r_link_params* lp = &m->link[i];
    const int gx = 2 * i, gy = 2 * i + 1;
    const double rd = k->rho_dot, td = k->theta_dot;
    F3R_AT(A, ld, gx, F3R_Q_RHO + i) += scale * (-2.0 * td * k->s);
    F3R_AT(A, ld, gy, F3R_Q_RHO + i) += scale * (2.0 * td * k->c);
    const double de = -2.0 * k->len * td - 2.0 * k->w_dot, dn = 2.0 * rd - 2.0 * k->w * td;
    F3R_AT(A, ld, gx, F3R_Q_THETA + i) += scale * (de * k->c - dn * k->s);
    F3R_AT(A, ld, gy, F3R_Q_THETA + i) += scale * (de * k->s + dn * k->c);
    for (int j = 0; j < lp->modes; ++j) {
      const int col = lp->eta_index + j;
      F3R_AT(A, ld, gx, col) += scale * (-2.0 * lp->tip[j] * td * k->c);
      F3R_AT(A, ld, gy, col) += scale * (-2.0 * lp->tip[j] * td * k->s);
    }
    F3R_AT(A, ld, gx, F3R_Q_PHI) += scale * (2.0 * m->platform_radius * pd * k->cc);
    F3R_AT(A, ld, gy, F3R_Q_PHI) += scale * (2.0 * m->platform_radius * pd * k->sc);
  }
}

void f3r_data_solve_dependent(const f3r_data* d, const double* V, int ncols, double scale,
                              double* x) {
  for (int j = 0; j < ncols; ++j) {
    const double* v = V + 6 * j;
    double rho[3], theta[3]; /* all read before x, which may be V, is written */
    for (int i = 0; i < 3; ++i)
      f3r_link_solve_dependent(&d->link[i], v[2 * i], v[2 * i + 1], &rho[i], &theta[i]);
    for (int i = 0; i < 3; ++i) {
      x[i + 6 * j] = scale * rho[i];
      x[F3R_Q_THETA + i + 6 * j] = scale * theta[i];
    }
  }
}

/* --- the public (q, v) functions of stages.h: the stages they need, then the kernels --------- */

enum { AT_Q = F3R_FWD_POSITION, AT_QV = F3R_FWD_POSITION | F3R_FWD_VELOCITY };

void f3r_constraints(const f3r_model* m, const double* q, double* g) {
  f3r_data d;
  memcpy(g, f3r_forward_at(m, q, NULL, AT_Q, &d)->g, sizeof d.g);
}

void f3r_constraint_bias(const f3r_model* m, const double* q, const double* v, double* gamma) {
  f3r_data d;
  memcpy(gamma, f3r_forward_at(m, q, v, AT_QV, &d)->gamma, sizeof d.gamma);
}

void f3r_add_constraint_jacobian(const f3r_model* m, const double* q, double scale, double* A,
                                 int ld) {
  f3r_data d;
  f3r_data_add_constraint_jacobian(m, f3r_forward_at(m, q, NULL, AT_Q, &d), scale, A, ld);
}

void f3r_add_constraint_jacobian_transpose(const f3r_model* m, const double* q, double scale,
                                           double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_jacobian_transpose(m, f3r_forward_at(m, q, NULL, AT_Q, &d), scale, A, ld);
}

void f3r_constraint_times(const f3r_model* m, const double* q, const double* v, double* out) {
  f3r_data d;
  f3r_data_constraint_times(m, f3r_forward_at(m, q, NULL, AT_Q, &d), v, out);
}

void f3r_constraint_transpose_times(const f3r_model* m, const double* q, const double* lambda,
                                    double* out) {
  f3r_data d;
  f3r_data_constraint_transpose_times(m, f3r_forward_at(m, q, NULL, AT_Q, &d), lambda, out);
}

void f3r_add_constraint_transpose_times_dq(const f3r_model* m, const double* q,
                                           const double* lambda, double scale, double* A, int ld) {
  f3r_data d;
  f3r_forward_at(m, q, NULL, AT_Q, &d);
  f3r_data_add_constraint_transpose_times_dq(m, &d, lambda, scale, A, ld);
}

void f3r_add_constraint_times_dq(const f3r_model* m, const double* q, const double* v, double scale,
                                 double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_times_dq(m, f3r_forward_at(m, q, v, AT_QV, &d), v, scale, A, ld);
}

void f3r_add_constraint_bias_dq(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_bias_dq(m, f3r_forward_at(m, q, v, AT_QV, &d), v, scale, A, ld);
}

void f3r_add_constraint_bias_dv(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld) {
  f3r_data d;
  f3r_data_add_constraint_bias_dv(m, f3r_forward_at(m, q, v, AT_QV, &d), v, scale, A, ld);
}

size_t f3r_solve_accelerations_work_size(const f3r_model* m) {
  const size_t n = (size_t)m->nq + F3R_NCON;
  return n * n + 2 * n + 2 * (size_t)F3R_MAX_Q;
}

void f3r_constrained_system(const f3r_model* m, const double* q, const double* v, const double* Q,
                            int n, double* K, double* b, double* elastic) {
  const int nq = m->nq;
  f3r_data d;
  f3r_forward_at(m, q, v, F3R_FWD_POSITION | F3R_FWD_VELOCITY, &d);
  for (size_t z = 0; z < (size_t)n * n; ++z) K[z] = 0.0;
  f3r_data_add_mass_matrix(m, &d, 1.0, K, n);
  f3r_data_add_constraint_jacobian_transpose(m, &d, -1.0, K + (size_t)nq * n,
                                             n);           /* -G^T, top right */
  f3r_data_add_constraint_jacobian(m, &d, 1.0, K + nq, n); /* G, bottom left */
  f3r_elastic_forces(m, q, elastic);
  for (int r = 0; r < nq; ++r) b[r] = Q[r] - d.h[r] - elastic[r];
  for (int c = 0; c < F3R_NCON; ++c) b[nq + c] = -d.gamma[c];
}

f3r_status f3r_solve_accelerations(const f3r_model* m, const double* q, const double* v,
                                   const double* Q, double* a, double* lambda, double* work) {
  const int nq = m->nq, n = nq + F3R_NCON;
  double* K = work;
  double* b = K + (size_t)n * n;
  int* piv = (int*)(b + n); /* n ints fit in n doubles */
  f3r_constrained_system(m, q, v, Q, n, K, b, b + 2 * n);
  if (f3r_lu_factor(K, n, piv)) return F3R_ERR_SINGULAR;
  f3r_lu_solve(K, n, piv, b);
  for (int r = 0; r < nq; ++r) a[r] = b[r];
  for (int c = 0; c < F3R_NCON; ++c) lambda[c] = b[nq + c];
  return F3R_OK;
}

/* The equations of motion assembled from one forward pass: see equations.h. M's blocks come from
 * the mass stage (mass.c), G's from the position stage (position.c):
 *   G_i: d/drho = e, d/dth = L n - w e, d/deta_j = psi_j(1) n, d/dP = -I, d/dphi_p = -r_PC n_c.
 * The minimal formulation (residual.h): per link, the dependent block of G is G_d = [e, L n - w e],
 * det = L = rho + l, so
 *   G_d x = V     gives  theta = (n.V)/L,  rho = e.V + w theta,
 *   G_d^T x = R   gives  x = R_rho e + ((R_theta + w R_rho)/L) n.
 * Accelerations: a_d = G_d^{-1} (-G_z a_z - gamma). The reduced equations B^T R = 0 are
 * R_z - G_z^T lambda with lambda = G_d^{-T} R_d, which is also the constraint force. */
#include "equations.h"
#include "dense.h"

/* --- M ------------------------------------------------------------------------------------------ */

void f3r_data_add_mass_matrix(const f3r_model* m, const f3r_data* d, double scale, double* A,
                              int ld) {
  const double mass = m->link_mass;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const int r = i, t = F3R_Q_THETA + i, base = m->link[i].eta_index;
    F3R_AT(A, ld, r, r) += scale * mass;
    F3R_AT(A, ld, r, t) += scale * k->m_rho_theta;
    F3R_AT(A, ld, t, r) += scale * k->m_rho_theta;
    F3R_AT(A, ld, t, t) += scale * k->m_theta_theta;
    for (int j = 0; j < m->link[i].modes; ++j) {
      F3R_AT(A, ld, t, base + j) += scale * k->m_theta_eta[j];
      F3R_AT(A, ld, base + j, t) += scale * k->m_theta_eta[j];
      F3R_AT(A, ld, base + j, base + j) += scale * mass;
    }
  }
  F3R_AT(A, ld, F3R_Q_X, F3R_Q_X) += scale * m->platform_mass;
  F3R_AT(A, ld, F3R_Q_Y, F3R_Q_Y) += scale * m->platform_mass;
  F3R_AT(A, ld, F3R_Q_PHI, F3R_Q_PHI) += scale * m->platform_inertia;
}

void f3r_data_mass_times(const f3r_model* m, const f3r_data* d, const double* x, double* out) {
  const double mass = m->link_mass;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const int base = m->link[i].eta_index;
    double coupled = 0.0;
    for (int j = 0; j < m->link[i].modes; ++j) {
      coupled += k->m_theta_eta[j] * x[base + j];
      out[base + j] = k->m_theta_eta[j] * x[F3R_Q_THETA + i] + mass * x[base + j];
    }
    out[i] = mass * x[i] + k->m_rho_theta * x[F3R_Q_THETA + i];
    out[F3R_Q_THETA + i] = k->m_rho_theta * x[i] + k->m_theta_theta * x[F3R_Q_THETA + i] + coupled;
  }
  out[6] = m->platform_mass * x[F3R_Q_X];
  out[7] = m->platform_mass * x[F3R_Q_Y];
  out[8] = m->platform_inertia * x[F3R_Q_PHI];
}

/* --- G ------------------------------------------------------------------------------------------ */

/* Calls put(row, col, value) for every nonzero of G, so G and G^T share one definition. */
#define F3R_FOR_EACH_G_ENTRY(m, d, PUT)            \
  for (int i = 0; i < 3; ++i) {                    \
    const f3r_link_data* k = &(d)->link[i];        \
    const int gx = 2 * i, gy = 2 * i + 1;          \
    PUT(gx, i, k->c);                              \
    PUT(gy, i, k->s);                              \
    PUT(gx, F3R_Q_THETA + i, k->g_theta[0]);       \
    PUT(gy, F3R_Q_THETA + i, k->g_theta[1]);       \
    PUT(gx, F3R_Q_X, -1.0);                        \
    PUT(gy, F3R_Q_Y, -1.0);                        \
    PUT(gx, F3R_Q_PHI, k->g_phi[0]);               \
    PUT(gy, F3R_Q_PHI, k->g_phi[1]);               \
    const f3r_link_params* lp = &(m)->link[i];     \
    if (lp->model == F3R_LINK_FIXED_FREE)          \
      for (int j = 0; j < lp->modes; ++j) {        \
        PUT(gx, lp->eta_index + j, k->g_eta_x[j]); \
        PUT(gy, lp->eta_index + j, k->g_eta_y[j]); \
      }                                            \
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

/* --- energies ------------------------------------------------------------------------------------ */

/* T = v^T M v / 2 and V = sum k_j eta_j^2 / 2. */
void f3r_energy_stage(const f3r_model* m, f3r_data* d) {
  double Mv[F3R_MAX_Q];
  f3r_data_mass_times(m, d, d->v, Mv);
  double T = 0.0;
  for (int n = 0; n < m->nq; ++n) T += 0.5 * d->v[n] * Mv[n];
  double V = 0.0;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    for (int j = 0; j < lp->modes; ++j) {
      const double eta = d->q[lp->eta_index + j];
      V += 0.5 * lp->stiffness[j] * eta * eta;
    }
  }
  d->kinetic = T;
  d->potential = V;
}

/* --- the constrained system ---------------------------------------------------------------------- */

size_t f3r_solve_accelerations_work_size(const f3r_model* m) {
  const size_t n = (size_t)m->nq + F3R_NCON;
  return n * n + 2 * n;
}

/* [M -G^T; G 0] (n x n, n >= nq + 6, all of K zeroed) and b = [Q - h - k; -gamma] (its first
 * nq + 6 rows): the accelerations' system, and the stops' with their rows after it. */
static void constrained_system(const f3r_model* m, const f3r_data* d, const double* Q, int n,
                               double* K, double* b) {
  const int nq = m->nq;
  for (size_t z = 0; z < (size_t)n * n; ++z) K[z] = 0.0;
  f3r_data_add_mass_matrix(m, d, 1.0, K, n);
  f3r_data_add_constraint_jacobian_transpose(m, d, -1.0, K + (size_t)nq * n, n); /* -G^T */
  f3r_data_add_constraint_jacobian(m, d, 1.0, K + nq, n);                        /* G */
  for (int r = 0; r < nq; ++r) b[r] = Q[r] - d->h[r] - d->k[r];
  for (int c = 0; c < F3R_NCON; ++c) b[nq + c] = -d->gamma[c];
}

f3r_status f3r_data_solve_accelerations(const f3r_model* m, const f3r_data* d, const double* Q,
                                        double* a, double* lambda, double* work) {
  const int nq = m->nq, n = nq + F3R_NCON;
  double* K = work;
  double* b = K + (size_t)n * n;
  int* piv = (int*)(b + n); /* n ints fit in n doubles */
  constrained_system(m, d, Q, n, K, b);
  if (f3r_lu_factor(K, n, piv)) return F3R_ERR_SINGULAR;
  f3r_lu_solve(K, n, piv, b);
  for (int r = 0; r < nq; ++r) a[r] = b[r];
  for (int c = 0; c < F3R_NCON; ++c) lambda[c] = b[nq + c];
  return F3R_OK;
}

/* --- end stops held as contact ---------------------------------------------------------------- */

int f3r_stop_locks_any(const f3r_stop_locks* locks) {
  return locks->side[0] || locks->side[1] || locks->side[2];
}

size_t f3r_stop_forces_work_size(const f3r_model* m) {
  const size_t n = (size_t)m->nq + F3R_NCON + 3;
  return n * n + 2 * n;
}

f3r_status f3r_data_contact_solve(const f3r_model* m, const f3r_data* d,
                                  const f3r_stop_locks* locks, const double* Q, double* f,
                                  double* a, double* work) {
  int legs[3], count = 0;
  for (int i = 0; i < 3; ++i) {
    f[i] = 0.0;
    if (locks->side[i]) legs[count++] = i;
  }
  if (!count && !a) return F3R_OK;
  const int nq = m->nq, n = nq + F3R_NCON + count;
  const double rate = F3R_STOP_BAUMGARTE_RATE;
  double* K = work;
  double* b = K + (size_t)n * n;
  int* piv = (int*)(b + n);             /* n ints fit in n doubles */
  constrained_system(m, d, Q, n, K, b); /* its E rows and columns below */
  for (int c = 0; c < count; ++c) {
    const int leg = legs[c], row = nq + F3R_NCON + c;
    const double stop = locks->side[leg] < 0 ? m->stroke_min : m->stroke_max;
    F3R_AT(K, n, leg, row) = -1.0; /* -E in the dynamic rows */
    F3R_AT(K, n, row, leg) = 1.0;  /* E^T a */
    b[row] = -(2.0 * rate * d->v[leg] + rate * rate * (d->q[leg] - stop));
  }
  if (f3r_lu_factor(K, n, piv)) return F3R_ERR_SINGULAR;
  f3r_lu_solve(K, n, piv, b);
  for (int c = 0; c < count; ++c) f[legs[c]] = b[nq + F3R_NCON + c];
  if (a)
    for (int r = 0; r < nq; ++r) a[r] = b[r];
  return F3R_OK;
}

f3r_status f3r_data_stop_forces(const f3r_model* m, const f3r_data* d, const f3r_stop_locks* locks,
                                const double* Q, double* f, double* work) {
  return f3r_data_contact_solve(m, d, locks, Q, f, NULL, work);
}

f3r_status f3r_stop_stage(const f3r_model* m, f3r_data* d) {
  double* f = d->stop_force;
  if (!d->locks || !f3r_stop_locks_any(d->locks)) {
    f[0] = f[1] = f[2] = 0.0;
    return F3R_OK;
  }
  const f3r_status st = f3r_data_stop_forces(m, d, d->locks, d->Q, f, d->stop_work);
  if (st != F3R_OK) return st;
  for (int i = 0; i < 3; ++i) {
    d->Q[i] += f[i];
    d->power += f[i] * d->v[i];
  }
  return F3R_OK;
}

/* --- the acceleration stages ---------------------------------------------------------------------- */

/* Open: R = M a + h + k - Q - G^T lambda at the given a and lambda; G^T mu and G v with mu. */
static void open_accelerations(const f3r_model* m, f3r_data* d) {
  double gt_lambda[F3R_MAX_Q];
  f3r_data_mass_times(m, d, d->vdot, d->R);
  f3r_data_constraint_transpose_times(m, d, d->multipliers, gt_lambda);
  for (int n = 0; n < m->nq; ++n) d->R[n] += d->h[n] + d->k[n] - d->Q[n] - gt_lambda[n];
  for (int c = 0; c < F3R_NCON; ++c) d->lambda[c] = d->multipliers[c];
  if (!d->mu) return;
  f3r_data_constraint_transpose_times(m, d, d->mu, d->gt_mu);
  f3r_data_constraint_times(m, d, d->v, d->gv);
}

/* Link i's dependent accelerations a_d = G_d^{-1} (-G_z a_z - gamma), with a_z in d->a; G_z a_z
 * summed as f3r_data_constraint_times sums it (its zero terms of a_d drop out exactly). */
static F3R_NO_VECTORIZE void link_accelerations(const f3r_model* m, int i, f3r_data* d) {
  const f3r_link_data* k = &d->link[i];
  const f3r_link_params* lp = &m->link[i];
  double* a = d->a;
  double gx = 0.0 - a[F3R_Q_X], gy = 0.0 - a[F3R_Q_Y];
  gx += k->g_phi[0] * a[F3R_Q_PHI];
  gy += k->g_phi[1] * a[F3R_Q_PHI];
  if (lp->model == F3R_LINK_FIXED_FREE)
    for (int j = 0; j < lp->modes; ++j) {
      gx += k->g_eta_x[j] * a[lp->eta_index + j];
      gy += k->g_eta_y[j] * a[lp->eta_index + j];
    }
  f3r_link_solve_dependent(k, -gx - d->gamma[2 * i], -gy - d->gamma[2 * i + 1], &a[i],
                           &a[F3R_Q_THETA + i]);
}

/* (lx, ly) = G_d^{-T} (r_rho, r_theta) = r_rho e + ((r_theta + w r_rho) / L) n: link k's loop
 * force from its dependent rows of R. */
F3R_INLINE void link_solve_dependent_transpose(const f3r_link_data* k, double r_rho, double r_theta,
                                               double* lx, double* ly) {
  const double c = k->c, s = k->s, along = r_rho, across = (r_theta + k->w * r_rho) / k->len;
  *lx = along * c - across * s;
  *ly = along * s + across * c;
}
/* Link i's rows of R = M a + h + k - Q (as f3r_data_mass_times and the force stage give them),
 * its loop force lambda_i = G_d^{-T} R_d and, into res_eta, its modal rows of the reduced
 * equations R_eta - (G^T lambda)_eta. */
static F3R_NO_VECTORIZE void link_loop_forces(const f3r_model* m, int i, f3r_data* d,
                                              double* res_eta) {
  const f3r_link_data* k = &d->link[i];
  const f3r_link_params* lp = &m->link[i];
  const double mass = m->link_mass, *a = d->a;
  const int rho_at = i, theta_at = F3R_Q_THETA + i, base = lp->eta_index;
  double* R = d->R;
  double coupled = 0.0;
  for (int j = 0; j < lp->modes; ++j) {
    const int n = base + j;
    coupled += k->m_theta_eta[j] * a[n];
    R[n] = k->m_theta_eta[j] * a[theta_at] + mass * a[n] + (d->h[n] + d->k[n] - d->Q[n]);
  }
  R[rho_at] = mass * a[rho_at] + k->m_rho_theta * a[theta_at] +
              (d->h[rho_at] + d->k[rho_at] - d->Q[rho_at]);
  R[theta_at] = k->m_rho_theta * a[rho_at] + k->m_theta_theta * a[theta_at] + coupled +
                (d->h[theta_at] + d->k[theta_at] - d->Q[theta_at]);
  link_solve_dependent_transpose(k, R[rho_at], R[theta_at], &d->lambda[2 * i],
                                 &d->lambda[2 * i + 1]);
  const double lx = d->lambda[2 * i], ly = d->lambda[2 * i + 1];
  if (!res_eta) return;
  const int tip = lp->model == F3R_LINK_FIXED_FREE;
  for (int j = 0; j < lp->modes; ++j) {
    double gt_lambda = 0.0;
    if (tip) gt_lambda += k->g_eta_x[j] * lx, gt_lambda += k->g_eta_y[j] * ly;
    res_eta[j] = R[base + j] - gt_lambda;
  }
}

/* One pass per link (equations.h), after the links' accelerations. */
static F3R_NO_VECTORIZE void closed_accelerations(const f3r_model* m, f3r_data* d,
                                                  const double* a_z, double* res_u) {
  const int nz = m->n_independent;
  double* a = d->a;
  for (int j = 0; j < nz; ++j) a[F3R_Q_INDEPENDENT + j] = a_z[j];
  double pose[3] = {0.0, 0.0, 0.0}; /* G_P^T lambda, summed as constraint_transpose_times */
  /* two passes: the three links' divisions then run side by side */
  for (int i = 0; i < 3; ++i) link_accelerations(m, i, d);
  for (int i = 0; i < 3; ++i) {
    link_loop_forces(m, i, d, res_u ? res_u + m->link[i].eta_index - F3R_Q_INDEPENDENT : NULL);
    const double lx = d->lambda[2 * i], ly = d->lambda[2 * i + 1];
    pose[0] += -1.0 * lx;
    pose[1] += -1.0 * ly;
    pose[2] += d->link[i].g_phi[0] * lx;
    pose[2] += d->link[i].g_phi[1] * ly;
  }
  const double inertia[3] = {m->platform_mass, m->platform_mass, m->platform_inertia};
  for (int c = 0; c < 3; ++c) {
    const int n = F3R_Q_INDEPENDENT + c;
    d->R[n] = inertia[c] * a[n] + (d->h[n] + d->k[n] - d->Q[n]);
    if (res_u) res_u[c] = d->R[n] - pose[c];
  }
}

void f3r_acceleration_stage(const f3r_model* m, f3r_data* d, int closed) {
  static const double at_rest[F3R_MAX_Q]; /* u' = 0: the explicit right-hand side's F_u(0) */
  if (closed)
    closed_accelerations(m, d, d->udot ? d->udot : at_rest, d->reduced);
  else
    open_accelerations(m, d);
}

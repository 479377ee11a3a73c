/* Inertia, velocity-dependent and elastic forces of the 3-RPR manipulator, from its energies.
 *
 * Kinetic energy of link i (eq. 9 with w = sum eta_j psi_j(x/l), m = rho_A l, modes orthonormal):
 *   T_i = 1/2 I_c th'^2 + 1/2 m rho'^2 + 1/2 J th'^2 + th' sum c_j eta_j' + 1/2 m |eta'|^2
 *         [exact kinematics: - m rho' th' s + 1/2 m th'^2 |eta|^2]
 *   J = m (l^2/3 + l rho + rho^2),  c_j = m (l a_j + rho b_j),  s = sum b_j eta_j,
 *   a_j = int xi psi_j, b_j = int psi_j.
 * The exact terms come from the axial velocity rho' - w th' of a beam point, which the paper's
 * eq. (9) drops. With e = 1 for exact kinematics and 0 otherwise, h = dM/dt v - dT/dq is
 *   h_rho = -1/2 m (l + 2 rho) th'^2 - (1 + e) m th' s'
 *   h_th  = m (l + 2 rho) rho' th' + (1 - e) m rho' s' + 2 e m th' eta.eta'
 *   h_eta_k = (1 + e) m rho' th' b_k - e m th'^2 eta_k
 * (the paper's F_c = -h, with its F_c_eta corrected as docs/model.md says). The platform
 * (eq. 10) adds diag(m_p, m_p, I_p) and no velocity terms. Bending energy (eq. 12):
 *   V = 1/2 sum EI/l^3 alpha_j^4 eta_j^2. */
#include <math.h>
#include <string.h>

#include "data.h"
#include "dense.h"

static double exact_flag(const f3r_model* m) { return m->exact_kinematics ? 1.0 : 0.0; }

/* --- the stages' per-link parts (forward.c) ------------------------------------------------- */

void f3r_link_mass_blocks(const f3r_model* m, int i, f3r_link_data* k, double rho) {
  const f3r_link_params* lp = &m->link[i];
  const double l = m->link_length, mass = m->link_mass, e = exact_flag(m);
  k->m_rho_theta = -e * mass * k->mean_defl;
  k->m_theta_theta =
      m->cylinder_inertia + mass * (l * l / 3.0 + l * rho + rho * rho) + e * mass * k->eta_sq;
  for (int j = 0; j < lp->modes; ++j)
    k->m_theta_eta[j] = mass * (l * lp->first_moment[j] + rho * lp->mean[j]);
}

void f3r_link_velocity_forces(const f3r_model* m, int i, f3r_data* d) {
  const f3r_link_params* lp = &m->link[i];
  const f3r_link_data* k = &d->link[i];
  const double* q = d->q;
  const double mass = m->link_mass, e = exact_flag(m);
  const double rd = k->rho_dot, td = k->theta_dot, arm = m->link_length + 2.0 * q[i];
  d->h[i] = -0.5 * mass * arm * td * td - (1.0 + e) * mass * td * k->mean_defl_dot;
  d->h[F3R_Q_THETA + i] = mass * arm * rd * td + (1.0 - e) * mass * rd * k->mean_defl_dot +
                          2.0 * e * mass * td * k->eta_eta_dot;
  for (int j = 0; j < lp->modes; ++j)
    d->h[lp->eta_index + j] =
        (1.0 + e) * mass * rd * td * lp->mean[j] - e * mass * td * td * q[lp->eta_index + j];
}

/* T = v^T M v / 2 and V = sum k_j eta_j^2 / 2. */
void f3r_data_energies(const f3r_model* m, f3r_data* d) {
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

/* --- kernels on the position stage ---------------------------------------------------------- */

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

void f3r_data_add_velocity_forces_dv(const f3r_model* m, const f3r_data* d, const double* q,
                                     double scale, double* A, int ld) {
  const double mass = m->link_mass, l = m->link_length, e = exact_flag(m);
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const f3r_link_params* lp = &m->link[i];
    const int r = i, t = F3R_Q_THETA + i;
    const double rd = k->rho_dot, td = k->theta_dot, arm = l + 2.0 * q[i];
    F3R_AT(A, ld, r, t) += scale * (-mass * arm * td - (1.0 + e) * mass * k->mean_defl_dot);
    F3R_AT(A, ld, t, r) += scale * (mass * arm * td + (1.0 - e) * mass * k->mean_defl_dot);
    F3R_AT(A, ld, t, t) += scale * (mass * arm * rd + 2.0 * e * mass * k->eta_eta_dot);
    for (int j = 0; j < lp->modes; ++j) {
      const int col = lp->eta_index + j;
      const double b = lp->mean[j], eta = q[col];
      F3R_AT(A, ld, r, col) += scale * (-(1.0 + e) * mass * td * b);
      F3R_AT(A, ld, t, col) += scale * ((1.0 - e) * mass * rd * b + 2.0 * e * mass * td * eta);
      F3R_AT(A, ld, col, r) += scale * ((1.0 + e) * mass * td * b);
      F3R_AT(A, ld, col, t) += scale * ((1.0 + e) * mass * rd * b - 2.0 * e * mass * td * eta);
    }
  }
}

/* --- the public (q, v) functions of stages.h: the stages they need, then the kernels --------- */

void f3r_add_mass_matrix(const f3r_model* m, const double* q, double scale, double* A, int ld) {
  f3r_data d;
  f3r_data_add_mass_matrix(m, f3r_forward_at(m, q, NULL, F3R_FWD_POSITION, &d), scale, A, ld);
}

void f3r_mass_times(const f3r_model* m, const double* q, const double* a, double* out) {
  f3r_data d;
  f3r_data_mass_times(m, f3r_forward_at(m, q, NULL, F3R_FWD_POSITION, &d), a, out);
}

/* d(M(q) a)/dq: M depends on rho (J and c_j) and, with exact kinematics, on eta; never on theta. */
void f3r_add_mass_times_dq(const f3r_model* m, const double* q, const double* a, double scale,
                           double* A, int ld) {
  const double mass = m->link_mass, l = m->link_length, e = exact_flag(m);
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    const int r = i, t = F3R_Q_THETA + i, base = lp->eta_index;
    const double rho = q[i];
    double d_theta_d_rho = mass * (l + 2.0 * rho) * a[t];
    for (int j = 0; j < lp->modes; ++j) {
      const int col = base + j;
      d_theta_d_rho += mass * lp->mean[j] * a[col];
      F3R_AT(A, ld, r, col) += scale * (-e * mass * lp->mean[j] * a[t]);
      F3R_AT(A, ld, t, col) +=
          scale * (-e * mass * lp->mean[j] * a[r] + 2.0 * e * mass * q[col] * a[t]);
      F3R_AT(A, ld, col, r) += scale * mass * lp->mean[j] * a[t];
    }
    F3R_AT(A, ld, t, r) += scale * d_theta_d_rho;
  }
}

void f3r_velocity_forces(const f3r_model* m, const double* q, const double* v, double* h) {
  f3r_data d;
  memcpy(h, f3r_forward_at(m, q, v, F3R_FWD_POSITION | F3R_FWD_VELOCITY, &d)->h,
         (size_t)m->nq * sizeof(double));
}

/* dh/dq: h depends on rho (the arm l + 2 rho) and, with exact kinematics, on eta. */
void f3r_add_velocity_forces_dq(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld) {
  const double mass = m->link_mass, e = exact_flag(m);
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    const int r = i, t = F3R_Q_THETA + i;
    const double rd = v[r], td = v[t];
    F3R_AT(A, ld, r, r) += scale * (-mass * td * td);
    F3R_AT(A, ld, t, r) += scale * (2.0 * mass * rd * td);
    if (e == 0.0) continue;
    for (int j = 0; j < lp->modes; ++j) {
      const int col = lp->eta_index + j;
      F3R_AT(A, ld, t, col) += scale * (2.0 * mass * td * v[col]);
      F3R_AT(A, ld, col, col) += scale * (-mass * td * td);
    }
  }
  (void)q;
}

void f3r_add_velocity_forces_dv(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld) {
  f3r_data d;
  f3r_forward_at(m, q, v, F3R_FWD_POSITION | F3R_FWD_VELOCITY, &d);
  f3r_data_add_velocity_forces_dv(m, &d, q, scale, A, ld);
}

void f3r_link_elastic_forces(const f3r_model* m, int i, const double* q, double* k) {
  const f3r_link_params* lp = &m->link[i];
  k[i] = k[F3R_Q_THETA + i] = 0.0;
  for (int j = 0; j < lp->modes; ++j)
    k[lp->eta_index + j] = lp->stiffness[j] * q[lp->eta_index + j];
}

void f3r_elastic_forces(const f3r_model* m, const double* q, double* k) {
  for (int n = F3R_Q_X; n < F3R_Q_MODAL; ++n) k[n] = 0.0;
  for (int i = 0; i < 3; ++i) f3r_link_elastic_forces(m, i, q, k);
}

void f3r_add_elastic_forces_dq(const f3r_model* m, double scale, double* A, int ld) {
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    for (int j = 0; j < lp->modes; ++j) {
      const int col = lp->eta_index + j;
      F3R_AT(A, ld, col, col) += scale * lp->stiffness[j];
    }
  }
}

void f3r_generalized_forces(const f3r_model* m, double t, const double* held, const double* q,
                            const double* v, double* Q) {
  f3r_data d;
  f3r_forward_at(m, q, v, F3R_FWD_POSITION, &d);
  d.t = t;
  for (int n = 0; n < m->nq; ++n) Q[n] = held ? held[n] : 0.0;
  f3r_effects_add_forces(m, &d, Q);
}

void f3r_applied_forces(const f3r_model* m, double t, const double* held, const double* q,
                        const double* v, const double* lag, double* Q, double* commanded) {
  f3r_data d = {.t = t, .q = q, .v = v, .held = held, .lag = lag};
  f3r_forward(m, &d, F3R_FWD_POSITION | F3R_FWD_FORCES);
  memcpy(Q, d.Q, (size_t)m->nq * sizeof(double));
  if (commanded && m->n_lag) memcpy(commanded, d.commanded, sizeof d.commanded);
}

double f3r_kinetic_energy(const f3r_model* m, const double* q, const double* v) {
  f3r_data d;
  return f3r_forward_at(m, q, v, F3R_FWD_POSITION | F3R_FWD_ENERGY, &d)->kinetic;
}

double f3r_potential_energy(const f3r_model* m, const double* q) {
  static const double at_rest[F3R_MAX_Q] = {0};
  f3r_data d;
  return f3r_forward_at(m, q, at_rest, F3R_FWD_POSITION | F3R_FWD_ENERGY, &d)->potential;
}

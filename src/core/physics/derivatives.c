/* The derivatives of the equations of motion (velocity.c's h, mass.c's M, forces.c's k and
 * position.c's g) that the Jacobians and the linear model need, analytic; the effects keep theirs
 * beside them (effects.c). test_stages checks each against finite differences of the queries. */
#include "derivatives.h"
#include "dense.h"

/* d(M(q) a)/dq: M depends on rho (J and c_j) and, with exact kinematics, on eta; never on theta. */
void f3r_add_mass_times_dq(const f3r_model* m, const double* q, const double* a, double scale,
                           double* A, int ld) {
  const double mass = m->link_mass, l = m->link_length, e = (m->exact_kinematics ? 1.0 : 0.0);
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

/* dh/dq: h depends on rho (the arm l + 2 rho) and, with exact kinematics, on eta. */
void f3r_add_velocity_forces_dq(const f3r_model* m, const double* q, const double* v, double scale,
                                double* A, int ld) {
  const double mass = m->link_mass, e = (m->exact_kinematics ? 1.0 : 0.0);
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

void f3r_data_add_velocity_forces_dv(const f3r_model* m, const f3r_data* d, const double* q,
                                     double scale, double* A, int ld) {
  const double mass = m->link_mass, l = m->link_length, e = (m->exact_kinematics ? 1.0 : 0.0);
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

void f3r_add_elastic_forces_dq(const f3r_model* m, double scale, double* A, int ld) {
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    for (int j = 0; j < lp->modes; ++j) {
      const int col = lp->eta_index + j;
      F3R_AT(A, ld, col, col) += scale * lp->stiffness[j];
    }
  }
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

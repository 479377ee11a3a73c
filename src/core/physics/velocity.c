/* The velocity stage: per link the rates of the modal sums, h = dM/dt v - dT/dq from the kinetic
 * energy (mass.c) and gamma = (dG/dt) v from g (position.c). With e = 1 for exact kinematics and
 * 0 otherwise, m the link's mass and s = sum b_j eta_j,
 *   h_rho = -1/2 m (l + 2 rho) th'^2 - (1 + e) m th' s'
 *   h_th  = m (l + 2 rho) rho' th' + (1 - e) m rho' s' + 2 e m th' eta.eta'
 *   h_eta_k = (1 + e) m rho' th' b_k - e m th'^2 eta_k
 * (the paper's F_c = -h, with its F_c_eta corrected as docs/model.md says); the platform has no
 * velocity terms. gamma_i = 2 rho' th' n - L th'^2 e - 2 w' th' e - w th'^2 n + r_PC phi'^2 e_c. */
#include <string.h>

#include "velocity.h"

/* Link i's rates of its modal sums; with `closed`, rho_i' and theta_i' in v_closed from G v = 0,
 * with C' the velocity of C_i: theta' = (n . C' - w') / L and rho' = e . C' + w theta'. */
static void link_rates(const f3r_model* m, int i, int closed, f3r_data* d) {
  const f3r_link_params* lp = &m->link[i];
  f3r_link_data* k = &d->link[i];
  const double *q = d->q, *v = d->v;
  /* the closed stage reads the independent rates from u, not from their copy in v */
  const double* eta_rate = closed ? d->u + lp->eta_index - F3R_Q_INDEPENDENT : v + lp->eta_index;
  double w_dot = 0.0, mean_defl_dot = 0.0, eta_eta_dot = 0.0; /* in locals, as modal_sums */
  for (int j = 0; j < lp->modes; ++j) {
    const double rate = eta_rate[j];
    w_dot += lp->tip[j] * rate;
    mean_defl_dot += lp->mean[j] * rate;
    eta_eta_dot += q[lp->eta_index + j] * rate;
  }
  k->w_dot = w_dot, k->mean_defl_dot = mean_defl_dot, k->eta_eta_dot = eta_eta_dot;
  if (closed) {
    const double r = m->platform_radius, *pose_rate = d->u;
    const double cx = pose_rate[0] - r * k->sc * pose_rate[2],
                 cy = pose_rate[1] + r * k->cc * pose_rate[2];
    const double theta_dot = (-k->s * cx + k->c * cy - k->w_dot) / k->len;
    d->v_closed[i] = k->c * cx + k->s * cy + k->w * theta_dot;
    d->v_closed[F3R_Q_THETA + i] = theta_dot;
  }
  k->rho_dot = v[i];
  k->theta_dot = v[F3R_Q_THETA + i];
}

/* Link i's rows of h (the header's comment). */
static void link_velocity_forces(const f3r_model* m, int i, f3r_data* d) {
  const f3r_link_params* lp = &m->link[i];
  const f3r_link_data* k = &d->link[i];
  const double* q = d->q;
  const double mass = m->link_mass, e = m->exact_kinematics ? 1.0 : 0.0;
  const double rd = k->rho_dot, td = k->theta_dot, arm = m->link_length + 2.0 * q[i];
  d->h[i] = -0.5 * mass * arm * td * td - (1.0 + e) * mass * td * k->mean_defl_dot;
  d->h[F3R_Q_THETA + i] = mass * arm * rd * td + (1.0 - e) * mass * rd * k->mean_defl_dot +
                          2.0 * e * mass * td * k->eta_eta_dot;
  for (int j = 0; j < lp->modes; ++j)
    d->h[lp->eta_index + j] =
        (1.0 + e) * mass * rd * td * lp->mean[j] - e * mass * td * td * q[lp->eta_index + j];
}

/* gamma_i = along e + across n + r_PC phi'^2 e_c (the header's comment). */
static void link_constraint_bias(const f3r_model* m, int i, f3r_data* d) {
  const f3r_link_data* k = &d->link[i];
  const double td = k->theta_dot, phi_dot = d->v[F3R_Q_PHI];
  const double along = -k->len * td * td - 2.0 * k->w_dot * td; /* e component */
  const double across = 2.0 * k->rho_dot * td - k->w * td * td; /* n component */
  const double rp = m->platform_radius * phi_dot * phi_dot;
  d->gamma[2 * i] = along * k->c - across * k->s + rp * k->cc;
  d->gamma[2 * i + 1] = along * k->s + across * k->c + rp * k->sc;
}

void f3r_velocity_stage(const f3r_model* m, f3r_data* d, int closed) {
  if (closed) { /* the independent rates copied whole, as the closed position stage does */
    memcpy(d->v_closed + F3R_Q_INDEPENDENT, d->u, (size_t)m->n_independent * sizeof(double));
    d->v = d->v_closed;
  }
  /* the rates first: each closed leg's ends in a division, and the three run side by side */
  for (int i = 0; i < 3; ++i) link_rates(m, i, closed, d);
  for (int i = 0; i < 3; ++i) {
    link_velocity_forces(m, i, d);
    link_constraint_bias(m, i, d);
  }
  d->h[F3R_Q_X] = d->h[F3R_Q_Y] = d->h[F3R_Q_PHI] = 0.0;
}

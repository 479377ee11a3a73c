/* The force stage. Bending energy (eq. 12): V = 1/2 sum EI/l^3 alpha_j^4 eta_j^2, so k = dV/dq is
 * nonzero on the modal coordinates only. Q = held + the effects (effects.c); with actuator lag the
 * legs' applied forces are the lag states, not the commanded held + scripted forces. */
#include "effects.h"
#include "forces.h"

/* k of link i's coordinates (rho_i, theta_i: zero; eta_i) into k (nq). */
static void link_elastic_forces(const f3r_model* m, int i, const double* q, double* k) {
  const f3r_link_params* lp = &m->link[i];
  k[i] = k[F3R_Q_THETA + i] = 0.0;
  for (int j = 0; j < lp->modes; ++j)
    k[lp->eta_index + j] = lp->stiffness[j] * q[lp->eta_index + j];
}

void f3r_elastic_forces(const f3r_model* m, const double* q, double* k) {
  for (int n = F3R_Q_X; n < F3R_Q_MODAL; ++n) k[n] = 0.0;
  for (int i = 0; i < 3; ++i) link_elastic_forces(m, i, q, k);
}

/* Link i's share: its elastic forces and the caller's held forces on its coordinates, which the
 * effects then add to. */
static void link_forces(const f3r_model* m, int i, f3r_data* d) {
  const f3r_link_params* lp = &m->link[i];
  const double* held = d->held;
  link_elastic_forces(m, i, d->q, d->k);
  const int t = F3R_Q_THETA + i;
  d->Q[i] = held ? held[i] : 0.0;
  d->Q[t] = held ? held[t] : 0.0;
  for (int j = 0; j < lp->modes; ++j) {
    const int n = lp->eta_index + j;
    d->Q[n] = held ? held[n] : 0.0;
  }
}

void f3r_force_stage(const f3r_model* m, f3r_data* d) {
  const int nq = m->nq;
  const double *held = d->held, *v = d->v;
  for (int i = 0; i < 3; ++i) link_forces(m, i, d);
  for (int n = F3R_Q_X; n < F3R_Q_MODAL; ++n) {
    d->k[n] = 0.0;
    d->Q[n] = held ? held[n] : 0.0;
  }
  if (m->n_lag) /* the inputs effect, when the scene has one, fills them */
    for (int n = 0; n < F3R_RIGID_FORCES; ++n) d->input[n] = 0.0;
  f3r_effects_add_forces(m, d, d->Q);
  if (m->n_lag)
    for (int i = 0; i < 3; ++i) {
      d->commanded[i] = (held ? held[i] : 0.0) + d->input[F3R_FORCE_RHO + i];
      d->Q[i] += (d->lag ? d->lag[i] : 0.0) - d->commanded[i];
    }
  double power = 0.0;
  for (int n = 0; n < nq; ++n) power += d->Q[n] * v[n];
  d->power = power;
}

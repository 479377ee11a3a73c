/* Per-link quantities that every stage needs, gathered once from q (and v). Private. */
#ifndef FLEX3RPR_LINK_STATE_H
#define FLEX3RPR_LINK_STATE_H

#include "flex3rpr/model.h"

typedef struct {
  double rho, theta;      /* stroke and leg direction */
  double c, s;            /* cos theta, sin theta: e = (c, s), n = (-s, c) */
  double len;             /* L = rho + l, distance from A_i to the beam's tip along e */
  double w;               /* tip deflection w_i(l) = sum tip_j eta_j */
  double mean_defl;       /* sum mean_j eta_j  = int_0^1 w dxi */
  double eta_sq;          /* sum eta_j^2 = int_0^1 w^2 dxi */
  const double* eta;      /* modal coordinates (NULL for a rigid link) */
  /* rates, filled only when v is given */
  double rho_dot, theta_dot;
  double w_dot, mean_defl_dot, eta_eta_dot; /* sum tip eta_dot, sum mean eta_dot, sum eta eta_dot */
  const double* eta_dot;
} f3r_link_state;

/* Platform joint C_i: angle phi_i + phi_p, e_c = (cc, sc), n_c = (-sc, cc). */
typedef struct {
  double cc, sc;
} f3r_platform_joint;

static inline void f3r_link_state_fill(const f3r_model* m, int i, const double* q,
                                       const double* v, f3r_link_state* k) {
  const f3r_link_params* lp = &m->link[i];
  k->rho = q[i];
  k->theta = q[3 + i];
  k->c = cos(k->theta);
  k->s = sin(k->theta);
  k->len = k->rho + m->link_length;
  k->w = k->mean_defl = k->eta_sq = 0.0;
  k->eta = lp->modes ? q + lp->eta_index : 0;
  for (int j = 0; j < lp->modes; ++j) {
    const double eta = q[lp->eta_index + j];
    k->w += lp->tip[j] * eta;
    k->mean_defl += lp->mean[j] * eta;
    k->eta_sq += eta * eta;
  }
  if (!v) return;
  k->rho_dot = v[i];
  k->theta_dot = v[3 + i];
  k->w_dot = k->mean_defl_dot = k->eta_eta_dot = 0.0;
  k->eta_dot = lp->modes ? v + lp->eta_index : 0;
  for (int j = 0; j < lp->modes; ++j) {
    const double rate = v[lp->eta_index + j];
    k->w_dot += lp->tip[j] * rate;
    k->mean_defl_dot += lp->mean[j] * rate;
    k->eta_eta_dot += q[lp->eta_index + j] * rate;
  }
}

static inline f3r_platform_joint f3r_platform_joint_at(const f3r_model* m, int i, const double* q) {
  const double angle = m->platform_angle[i] + q[8];
  f3r_platform_joint pj = {cos(angle), sin(angle)};
  return pj;
}

#endif

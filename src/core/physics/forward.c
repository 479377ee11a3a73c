/* The forward pass: the stages that fill f3r_data (data.h), in order.
 *   position   q                 -> per link c, s, L, w, modal sums, mass and constraint blocks;
 *                                   the platform joints' directions; g
 *   velocity   v + position      -> per link rates; h; gamma
 *   forces     t + the above     -> k, Q (held, effects, actuator lag), power
 *   formulation (form_dae.c, form_minimal.c) -> residual rows, accelerations, multipliers
 * The trigonometry: one sin/cos pair for phi_p, rotated onto the three platform joints, and one
 * per leg angle from q, or none in the minimal formulation, whose loop closure gives each leg's
 * direction algebraically. Equations: dynamics.c (inertia, h), constraints.c (G, gamma). */
#include <math.h>

#include "data.h"

static double exact_flag(const f3r_model* m) { return m->exact_kinematics ? 1.0 : 0.0; }

/* (cc, sc) of platform joint i from (cos, sin) phi_p: its direction at phi_p = 0, rotated. */
static void joint_direction(const f3r_model* m, int i, double cp, double sp, double* cc,
                            double* sc) {
  const double c0 = m->platform_direction[i][0], s0 = m->platform_direction[i][1];
  *cc = c0 * cp - s0 * sp;
  *sc = s0 * cp + c0 * sp;
}

/* (cc, sc) of the three platform joints from one sin/cos pair of phi_p. */
static void platform_joints(const f3r_model* m, double phi_p, f3r_data* d) {
  const double cp = cos(phi_p), sp = sin(phi_p);
  d->sincos_pairs++;
  for (int i = 0; i < 3; ++i) joint_direction(m, i, cp, sp, &d->link[i].cc, &d->link[i].sc);
}

/* w, the mean deflection and |eta|^2 of link i. */
static void modal_sums(const f3r_model* m, int i, const double* q, f3r_link_data* k) {
  const f3r_link_params* lp = &m->link[i];
  k->w = k->mean_defl = k->eta_sq = 0.0;
  for (int j = 0; j < lp->modes; ++j) {
    const double eta = q[lp->eta_index + j];
    k->w += lp->tip[j] * eta;
    k->mean_defl += lp->mean[j] * eta;
    k->eta_sq += eta * eta;
  }
}

/* The mass blocks of link i at stroke rho (dynamics.c: the kinetic energy T_i). */
static void mass_blocks(const f3r_model* m, int i, double rho, f3r_link_data* k) {
  const f3r_link_params* lp = &m->link[i];
  const double l = m->link_length, mass = m->link_mass, e = exact_flag(m);
  k->m_rho_theta = -e * mass * k->mean_defl;
  k->m_theta_theta =
      m->cylinder_inertia + mass * (l * l / 3.0 + l * rho + rho * rho) + e * mass * k->eta_sq;
  for (int j = 0; j < lp->modes; ++j)
    k->m_theta_eta[j] = mass * (l * lp->first_moment[j] + rho * lp->mean[j]);
}

/* The constraint Jacobian blocks that depend on the directions (constraints.c). */
static void constraint_blocks(const f3r_model* m, f3r_link_data* k) {
  k->g_theta[0] = -k->len * k->s - k->w * k->c;
  k->g_theta[1] = k->len * k->c - k->w * k->s;
  k->g_phi[0] = m->platform_radius * k->sc;
  k->g_phi[1] = -m->platform_radius * k->cc;
}

void f3r_fwd_position(const f3r_model* m, const double* q, f3r_data* d) {
  platform_joints(m, q[F3R_Q_PHI], d);
  for (int i = 0; i < 3; ++i) {
    f3r_link_data* k = &d->link[i];
    k->c = cos(q[F3R_Q_THETA + i]);
    k->s = sin(q[F3R_Q_THETA + i]);
    d->sincos_pairs++;
    k->len = q[i] + m->link_length;
    modal_sums(m, i, q, k);
    mass_blocks(m, i, q[i], k);
    constraint_blocks(m, k);
    const double r = m->platform_radius;
    d->g[2 * i] = m->base_joint[i][0] + k->len * k->c - k->w * k->s - q[F3R_Q_X] - r * k->cc;
    d->g[2 * i + 1] = m->base_joint[i][1] + k->len * k->s + k->w * k->c - q[F3R_Q_Y] - r * k->sc;
  }
}

/* D = C_i - A_i of leg i, from the platform pose in q and the joint direction (cc, sc). */
static void leg_span(const f3r_model* m, int i, const double* q, double cc, double sc, double* dx,
                     double* dy) {
  *dx = q[F3R_Q_X] + m->platform_radius * cc - m->base_joint[i][0];
  *dy = q[F3R_Q_Y] + m->platform_radius * sc - m->base_joint[i][1];
}

/* Each loop closes in closed form: with D = C_i - A_i, |D|^2 = L^2 + w^2, and D points along
 * theta_i + beta with tan beta = w / L, so e = (D_x L + D_y w, D_y L - D_x w) / |D|^2. */
f3r_status f3r_fwd_position_closed(const f3r_model* m, double* q, f3r_data* d) {
  platform_joints(m, q[F3R_Q_PHI], d);
  const double min_len = F3R_CLOSURE_MIN_LEG_FRACTION * m->link_length;
  for (int i = 0; i < 3; ++i) {
    f3r_link_data* k = &d->link[i];
    modal_sums(m, i, q, k);
    double dx, dy;
    leg_span(m, i, q, k->cc, k->sc, &dx, &dy);
    const double d_sq = dx * dx + dy * dy;
    const double len_sq = d_sq - k->w * k->w;
    if (!(len_sq > min_len * min_len)) return F3R_ERR_SINGULAR;
    const double len = sqrt(len_sq);
    q[i] = len - m->link_length;
    k->len = q[i] + m->link_length;
    k->c = (dx * len + dy * k->w) / d_sq;
    k->s = (dy * len - dx * k->w) / d_sq;
    mass_blocks(m, i, q[i], k);
    constraint_blocks(m, k);
    d->g[2 * i] = d->g[2 * i + 1] = 0.0;
  }
  return F3R_OK;
}

f3r_status f3r_fwd_leg_strokes(const f3r_model* m, const double* q, double rho[3]) {
  /* platform_joints' rotation, without an f3r_data to clear (kilobytes, more than the rest) */
  const double cp = cos(q[F3R_Q_PHI]), sp = sin(q[F3R_Q_PHI]);
  const double min_len = F3R_CLOSURE_MIN_LEG_FRACTION * m->link_length;
  for (int i = 0; i < 3; ++i) {
    const double w = f3r_model_tip_deflection(m, q, i); /* summed as modal_sums sums it */
    double cc, sc, dx, dy;
    joint_direction(m, i, cp, sp, &cc, &sc);
    leg_span(m, i, q, cc, sc, &dx, &dy);
    const double len_sq = dx * dx + dy * dy - w * w;
    if (!(len_sq > min_len * min_len)) return F3R_ERR_SINGULAR;
    rho[i] = sqrt(len_sq) - m->link_length;
  }
  return F3R_OK;
}

void f3r_fwd_leg_angles(const f3r_model* m, const f3r_data* d, double* q) {
  for (int i = 0; i < 3; ++i) {
    const double raw = atan2(d->link[i].s, d->link[i].c);
    q[F3R_Q_THETA + i] = m->theta_branch[i] + remainder(raw - m->theta_branch[i], 2.0 * M_PI);
  }
}

/* Rates of link i's modal sums, h and gamma (dynamics.c, constraints.c), with rho', theta' set. */
static void link_velocity(const f3r_model* m, int i, const double* q, const double* v,
                          f3r_data* d) {
  const f3r_link_params* lp = &m->link[i];
  f3r_link_data* k = &d->link[i];
  const double mass = m->link_mass, e = exact_flag(m);
  k->w_dot = k->mean_defl_dot = k->eta_eta_dot = 0.0;
  for (int j = 0; j < lp->modes; ++j) {
    const double rate = v[lp->eta_index + j];
    k->w_dot += lp->tip[j] * rate;
    k->mean_defl_dot += lp->mean[j] * rate;
    k->eta_eta_dot += q[lp->eta_index + j] * rate;
  }
  const double rd = k->rho_dot, td = k->theta_dot, arm = m->link_length + 2.0 * q[i];
  d->h[i] = -0.5 * mass * arm * td * td - (1.0 + e) * mass * td * k->mean_defl_dot;
  d->h[F3R_Q_THETA + i] = mass * arm * rd * td + (1.0 - e) * mass * rd * k->mean_defl_dot +
                          2.0 * e * mass * td * k->eta_eta_dot;
  for (int j = 0; j < lp->modes; ++j)
    d->h[lp->eta_index + j] =
        (1.0 + e) * mass * rd * td * lp->mean[j] - e * mass * td * td * q[lp->eta_index + j];
  const double along = -k->len * td * td - 2.0 * k->w_dot * td; /* e component */
  const double across = 2.0 * rd * td - k->w * td * td;         /* n component */
  const double rp = m->platform_radius * v[F3R_Q_PHI] * v[F3R_Q_PHI];
  d->gamma[2 * i] = along * k->c - across * k->s + rp * k->cc;
  d->gamma[2 * i + 1] = along * k->s + across * k->c + rp * k->sc;
}

void f3r_fwd_velocity(const f3r_model* m, const double* q, const double* v, f3r_data* d) {
  for (int i = 0; i < 3; ++i) {
    d->link[i].rho_dot = v[i];
    d->link[i].theta_dot = v[F3R_Q_THETA + i];
    link_velocity(m, i, q, v, d);
  }
  d->h[F3R_Q_X] = d->h[F3R_Q_Y] = d->h[F3R_Q_PHI] = 0.0;
}

/* From G v = 0 for link i, with C' the velocity of C_i and w' the tip deflection rate:
 * theta' = (n . C' - w') / L and rho' = e . C' + w theta'. */
void f3r_fwd_velocity_closed(const f3r_model* m, const double* q, double* v, f3r_data* d) {
  const double r = m->platform_radius;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    f3r_link_data* k = &d->link[i];
    double w_dot = 0.0;
    for (int j = 0; j < lp->modes; ++j) w_dot += lp->tip[j] * v[lp->eta_index + j];
    const double cx = v[F3R_Q_X] - r * k->sc * v[F3R_Q_PHI],
                 cy = v[F3R_Q_Y] + r * k->cc * v[F3R_Q_PHI];
    const double theta_dot = (-k->s * cx + k->c * cy - w_dot) / k->len;
    v[i] = k->c * cx + k->s * cy + k->w * theta_dot;
    v[F3R_Q_THETA + i] = theta_dot;
  }
  f3r_fwd_velocity(m, q, v, d);
}

void f3r_fwd_forces(const f3r_model* m, double t, const double* held, const double* q,
                    const double* v, const double* lag, f3r_data* d) {
  const int nq = m->nq;
  for (int n = 0; n < F3R_Q_MODAL; ++n) d->k[n] = 0.0;
  for (int i = 0; i < 3; ++i) {
    const f3r_link_params* lp = &m->link[i];
    for (int j = 0; j < lp->modes; ++j)
      d->k[lp->eta_index + j] = lp->stiffness[j] * q[lp->eta_index + j];
  }
  for (int n = 0; n < nq; ++n) d->Q[n] = held ? held[n] : 0.0;
  for (int e = 0; e < m->n_effects; ++e) m->effects[e]->add(m, t, q, v, d, d->Q);
  if (m->n_lag)
    for (int i = 0; i < 3; ++i) {
      d->commanded[i] =
          (held ? held[i] : 0.0) + f3r_input_value(&m->scene.inputs[F3R_FORCE_RHO + i], t);
      d->Q[i] += (lag ? lag[i] : 0.0) - d->commanded[i];
    }
  double power = 0.0;
  for (int n = 0; n < nq; ++n) power += d->Q[n] * v[n];
  d->power = power;
}

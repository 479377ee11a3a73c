/* The forward pass: f3r_forward runs the stages a caller asks for on the inputs in f3r_data
 * (data.h), in one pass per link where the stages allow it.
 *   position   q                 -> per link c, s, L, w, modal sums, mass and constraint blocks;
 *                                   the platform joints' directions; g
 *   (closed)   z                 -> the same, with rho_i and the legs' directions from the loop
 *                                   closure (the minimal formulation), q = q_closed
 *   velocity   v + position      -> per link rates; h; gamma
 *   (closed)   u + position      -> rho_i', theta_i' from G v = 0, then as velocity, v = v_closed
 *   forces     t + the above     -> k, Q (held, effects, actuator lag), power
 *   energy     the above         -> T, V
 *   formulation (form_dae.c, form_minimal.c) -> residual rows, accelerations, multipliers
 * The trigonometry: one sin/cos pair for phi_p, rotated onto the three platform joints, and one
 * per leg angle from q, or none in the closed stage, whose loop closure gives each leg's
 * direction algebraically. The per-link equations sit beside their derivatives: mass blocks and
 * h in dynamics.c, G's blocks, g and gamma in constraints.c. */
#include <math.h>
#include <string.h>

#include "data.h"

/* The stages' per-link parts below run once per link and evaluation; as calls they cost about 5 %
 * of a minimal residual at r = 3 (f3r_microbench), so they are forced inline (F3R_INLINE). (Forcing
 * the kernels of dynamics.c and constraints.c inline too, across files under -flto, gained 3 %
 * more at r = 3 and lost 2 % at r = 20.) */
#define STAGE F3R_INLINE

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

/* w, the mean deflection and |eta|^2 of link i from its modal coordinates eta, summed in locals
 * (a store into k could alias the model's tables, so summing into k would store at every mode). */
static void modal_sums(const f3r_model* m, int i, const double* eta, f3r_link_data* k) {
  const f3r_link_params* lp = &m->link[i];
  double w = 0.0, mean_defl = 0.0, eta_sq = 0.0;
  for (int j = 0; j < lp->modes; ++j) {
    w += lp->tip[j] * eta[j];
    mean_defl += lp->mean[j] * eta[j];
    eta_sq += eta[j] * eta[j];
  }
  k->w = w, k->mean_defl = mean_defl, k->eta_sq = eta_sq;
}

/* Position stage of link i from the full coordinates d->q. */
static void link_position(const f3r_model* m, int i, f3r_data* d) {
  const double* q = d->q;
  f3r_link_data* k = &d->link[i];
  k->c = cos(q[F3R_Q_THETA + i]);
  k->s = sin(q[F3R_Q_THETA + i]);
  d->sincos_pairs++;
  k->len = q[i] + m->link_length;
  modal_sums(m, i, q + m->link[i].eta_index, k);
  f3r_link_mass_blocks(m, i, k, q[i]);
  f3r_link_constraints(m, i, d, 0);
}

/* D = C_i - A_i of leg i, from the platform position (x, y) and the joint direction (cc, sc). */
static void leg_span(const f3r_model* m, int i, double x, double y, double cc, double sc,
                     double* dx, double* dy) {
  *dx = x + m->platform_radius * cc - m->base_joint[i][0];
  *dy = y + m->platform_radius * sc - m->base_joint[i][1];
}

/* Closed position stage of link i (z already in q_closed): the loop closes in closed form: with D = C_i - A_i, |D|^2 = L^2 + w^2, and D points along theta_i +
 * beta with tan beta = w / L, so e = (D_x L + D_y w, D_y L - D_x w) / |D|^2. */
static f3r_status link_position_closed(const f3r_model* m, int i, f3r_data* d) {
  double* q = d->q_closed;
  const double* z = d->z; /* read from z, not from its copy in q (open_closed_stages) */
  f3r_link_data* k = &d->link[i];
  modal_sums(m, i, z + m->link[i].eta_index - F3R_Q_INDEPENDENT, k);
  double dx, dy;
  leg_span(m, i, z[F3R_Q_X - F3R_Q_INDEPENDENT], z[F3R_Q_Y - F3R_Q_INDEPENDENT], k->cc, k->sc, &dx,
           &dy);
  const double d_sq = dx * dx + dy * dy;
  const double len_sq = d_sq - k->w * k->w;
  const double min_len = F3R_CLOSURE_MIN_LEG_FRACTION * m->link_length;
  if (!(len_sq > min_len * min_len)) return F3R_ERR_SINGULAR;
  const double len = sqrt(len_sq);
  q[i] = len - m->link_length;
  k->len = q[i] + m->link_length;
  k->c = (dx * len + dy * k->w) / d_sq;
  k->s = (dy * len - dx * k->w) / d_sq;
  return F3R_OK;
}

/* Velocity stage of link i: the rates of its modal sums; with `closed`, rho_i' and theta_i' in
 * v_closed from G v = 0, with C' the velocity of C_i: theta' = (n . C' - w') / L and
 * rho' = e . C' + w theta'. h and gamma follow in link_velocity_forces. */
STAGE void link_velocity(const f3r_model* m, int i, int closed, f3r_data* d) {
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

/* Link i's velocity-dependent forces h and constraint bias gamma, from its rates. */
static void link_velocity_forces(const f3r_model* m, int i, f3r_data* d) {
  f3r_link_velocity_forces(m, i, d);
  f3r_link_constraint_bias(m, i, d);
}

/* Link i's share of the force stage: its elastic forces and the caller's held forces on its
 * coordinates, which the effects then add to. */
STAGE void link_forces(const f3r_model* m, int i, f3r_data* d) {
  const f3r_link_params* lp = &m->link[i];
  const double* held = d->held;
  f3r_link_elastic_forces(m, i, d->q, d->k);
  const int t = F3R_Q_THETA + i;
  d->Q[i] = held ? held[i] : 0.0;
  d->Q[t] = held ? held[t] : 0.0;
  for (int j = 0; j < lp->modes; ++j) {
    const int n = lp->eta_index + j;
    d->Q[n] = held ? held[n] : 0.0;
  }
}

/* The force stage after the links': the platform's share, the effects, the actuator lag (the
 * commanded leg forces) and the power Q . v. */
STAGE void forces(const f3r_model* m, f3r_data* d) {
  const int nq = m->nq;
  const double *held = d->held, *v = d->v;
  for (int n = F3R_Q_X; n < F3R_Q_MODAL; ++n) {
    d->k[n] = 0.0;
    d->Q[n] = held ? held[n] : 0.0;
  }
  f3r_effects_add_forces(m, d, d->Q);
  if (m->n_lag)
    for (int i = 0; i < 3; ++i) {
      d->commanded[i] =
          (held ? held[i] : 0.0) + f3r_input_value(&m->scene.inputs[F3R_FORCE_RHO + i], d->t);
      d->Q[i] += (d->lag ? d->lag[i] : 0.0) - d->commanded[i];
    }
  double power = 0.0;
  for (int n = 0; n < nq; ++n) power += d->Q[n] * v[n];
  d->power = power;
}

/* The closed stages start from the independent coordinates and rates, copied whole (one copy
 * measured faster than each link's share in its pass). The stages right after read z and u
 * themselves: a load from the copy waited for memcpy's wide stores (4 ns a residual). */
static void open_closed_stages(const f3r_model* m, unsigned what, f3r_data* d) {
  const size_t nz = (size_t)m->n_independent;
  if (what & F3R_FWD_POSITION_CLOSED) {
    memcpy(d->q_closed + F3R_Q_INDEPENDENT, d->z, nz * sizeof(double));
    d->q = d->q_closed;
  }
  if (what & F3R_FWD_VELOCITY_CLOSED) {
    memcpy(d->v_closed + F3R_Q_INDEPENDENT, d->u, nz * sizeof(double));
    d->v = d->v_closed;
  }
}

f3r_status f3r_forward(const f3r_model* m, f3r_data* d, unsigned what) {
  const int closed_q = (what & F3R_FWD_POSITION_CLOSED) != 0;
  const int closed_v = (what & F3R_FWD_VELOCITY_CLOSED) != 0;
  const int velocity = closed_v || (what & F3R_FWD_VELOCITY);
  open_closed_stages(m, what, d);
  if (closed_q)
    platform_joints(m, d->z[F3R_Q_PHI - F3R_Q_INDEPENDENT], d);
  else if (what & F3R_FWD_POSITION)
    platform_joints(m, d->q[F3R_Q_PHI], d);
  /* Stage by stage over the three links, and the closed stages split after their divisions:
   * each leg's closure ends in a square root and two divisions, its rates in one more, and the
   * three legs' run side by side only when nothing that depends on them stands between (one pass
   * per link measured slower, f3r_microbench: 8 ns a residual for the two splits). */
  for (int i = 0; i < 3; ++i) {
    if (closed_q) {
      const f3r_status st = link_position_closed(m, i, d);
      if (st != F3R_OK) return st;
    } else if (what & F3R_FWD_POSITION) {
      link_position(m, i, d);
    }
  }
  if (closed_q)
    for (int i = 0; i < 3; ++i) {
      f3r_link_mass_blocks(m, i, &d->link[i], d->q[i]);
      f3r_link_constraints(m, i, d, 1);
    }
  if (velocity)
    for (int i = 0; i < 3; ++i) link_velocity(m, i, closed_v, d);
  for (int i = 0; i < 3; ++i) {
    if (velocity) link_velocity_forces(m, i, d);
    if (what & F3R_FWD_FORCES) link_forces(m, i, d);
  }
  if (velocity) d->h[F3R_Q_X] = d->h[F3R_Q_Y] = d->h[F3R_Q_PHI] = 0.0;
  if (what & F3R_FWD_FORCES) forces(m, d);
  if (what & F3R_FWD_ENERGY) f3r_data_energies(m, d);
  return F3R_OK;
}

const f3r_data* f3r_forward_at(const f3r_model* m, const double* q, const double* v, unsigned what,
                               f3r_data* d) {
  *d = (f3r_data){.q = q, .v = v};
  f3r_forward(m, d, what);
  return d;
}

f3r_status f3r_fwd_leg_strokes(const f3r_model* m, const double* q, double rho[3]) {
  /* platform_joints' rotation, without an f3r_data to clear (kilobytes, more than the rest) */
  const double cp = cos(q[F3R_Q_PHI]), sp = sin(q[F3R_Q_PHI]);
  const double min_len = F3R_CLOSURE_MIN_LEG_FRACTION * m->link_length;
  for (int i = 0; i < 3; ++i) {
    const double w = f3r_model_tip_deflection(m, q, i); /* summed as modal_sums sums it */
    double cc, sc, dx, dy;
    joint_direction(m, i, cp, sp, &cc, &sc);
    leg_span(m, i, q[F3R_Q_X], q[F3R_Q_Y], cc, sc, &dx, &dy);
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

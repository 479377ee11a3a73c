/* The position stage: per link e = (c, s), L = rho + l, w and the modal sums, the platform joints'
 * directions (cc, sc), G's direction-dependent blocks and g (paper eqs. 13-17; docs/model.md):
 *   g_i = A_i + L e + w n - P - r_PC e_c,   n = (-s, c), e_c = (cc, sc), n_c its normal,
 *   G_i: d/drho = e, d/dth = L n - w e, d/deta_j = psi_j(1) n, d/dP = -I, d/dphi_p = -r_PC n_c.
 * The trigonometry: one sin/cos pair for phi_p, rotated onto the three platform joints, and one
 * per leg angle from q, or none in the closed stage, whose loop closure gives each leg's direction
 * algebraically. */
#include <math.h>
#include <string.h>

#include "position.h"

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

/* G's direction-dependent blocks of link i and its g rows (zero when `closed`: the closure
 * satisfies them). */
static void link_constraints(const f3r_model* m, int i, f3r_data* d, int closed) {
  f3r_link_data* k = &d->link[i];
  const double r = m->platform_radius;
  k->g_theta[0] = -k->len * k->s - k->w * k->c;
  k->g_theta[1] = k->len * k->c - k->w * k->s;
  k->g_phi[0] = r * k->sc;
  k->g_phi[1] = -r * k->cc;
  const f3r_link_params* lp = &m->link[i];
  if (lp->model == F3R_LINK_FIXED_FREE)
    for (int j = 0; j < lp->modes; ++j) {
      k->g_eta_x[j] = -lp->tip[j] * k->s;
      k->g_eta_y[j] = lp->tip[j] * k->c;
    }
  if (closed) {
    d->g[2 * i] = d->g[2 * i + 1] = 0.0;
    return;
  }
  const double* q = d->q;
  d->g[2 * i] = m->base_joint[i][0] + k->len * k->c - k->w * k->s - q[F3R_Q_X] - r * k->cc;
  d->g[2 * i + 1] = m->base_joint[i][1] + k->len * k->s + k->w * k->c - q[F3R_Q_Y] - r * k->sc;
}

/* Link i from the full coordinates d->q. */
static void link_position(const f3r_model* m, int i, f3r_data* d) {
  const double* q = d->q;
  f3r_link_data* k = &d->link[i];
  k->c = cos(q[F3R_Q_THETA + i]);
  k->s = sin(q[F3R_Q_THETA + i]);
  d->sincos_pairs++;
  k->len = q[i] + m->link_length;
  modal_sums(m, i, q + m->link[i].eta_index, k);
  link_constraints(m, i, d, 0);
}

void f3r_position_stage(const f3r_model* m, f3r_data* d) {
  platform_joints(m, d->q[F3R_Q_PHI], d);
  for (int i = 0; i < 3; ++i) link_position(m, i, d);
}

/* D = C_i - A_i of leg i, from the platform position (x, y) and the joint direction (cc, sc). */
static void leg_span(const f3r_model* m, int i, double x, double y, double cc, double sc,
                     double* dx, double* dy) {
  *dx = x + m->platform_radius * cc - m->base_joint[i][0];
  *dy = y + m->platform_radius * sc - m->base_joint[i][1];
}

/* Link i closed (z already in q_closed): with D = C_i - A_i, |D|^2 = L^2 + w^2, and D points
 * along theta_i + beta with tan beta = w / L, so e = (D_x L + D_y w, D_y L - D_x w) / |D|^2. */
static f3r_status link_position_closed(const f3r_model* m, int i, f3r_data* d) {
  double* q = d->q_closed;
  const double* z = d->z; /* read from z, not from its copy in q (a load from the copy waited for
                           * memcpy's wide stores) */
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

f3r_status f3r_position_stage_closed(const f3r_model* m, f3r_data* d) {
  /* the independent coordinates copied whole (one copy measured faster than each link's share) */
  memcpy(d->q_closed + F3R_Q_INDEPENDENT, d->z, (size_t)m->n_independent * sizeof(double));
  d->q = d->q_closed;
  platform_joints(m, d->z[F3R_Q_PHI - F3R_Q_INDEPENDENT], d);
  /* the closures first, then the blocks: each closure ends in a square root and two divisions,
   * and the three legs' run side by side only when nothing that depends on them stands between */
  for (int i = 0; i < 3; ++i) {
    const f3r_status st = link_position_closed(m, i, d);
    if (st != F3R_OK) return st;
  }
  for (int i = 0; i < 3; ++i) link_constraints(m, i, d, 1);
  return F3R_OK;
}

double f3r_model_tip_deflection(const f3r_model* m, const double* q, int link) {
  const f3r_link_params* lp = &m->link[link];
  double w = 0.0;
  for (int j = 0; j < lp->modes; ++j) w += lp->tip[j] * q[lp->eta_index + j];
  return w;
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

/* Eigenvalues of a symmetric 3 x 3 matrix, by the trigonometric solution of its characteristic
 * cubic (Smith 1961); ascending in ev. */
static void symmetric_eigenvalues3(const double a[3][3], double ev[3]) {
  const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
  const double tr = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
  const double p2 = (a[0][0] - tr) * (a[0][0] - tr) + (a[1][1] - tr) * (a[1][1] - tr) +
                    (a[2][2] - tr) * (a[2][2] - tr) + 2.0 * p1;
  const double p = sqrt(p2 / 6.0);
  if (p == 0.0) {
    ev[0] = ev[1] = ev[2] = tr;
    return;
  }
  double b[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) b[i][j] = (a[i][j] - (i == j ? tr : 0.0)) / p;
  const double det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                     b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                     b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
  const double r = fmax(-1.0, fmin(1.0, det / 2.0));
  const double phi = acos(r) / 3.0;
  ev[2] = tr + 2.0 * p * cos(phi);
  ev[0] = tr + 2.0 * p * cos(phi + 2.0 * M_PI / 3.0);
  ev[1] = 3.0 * tr - ev[0] - ev[2];
}

double f3r_data_actuation_condition(const f3r_model* m, const f3r_data* d, const double* q) {
  double J[3][3]; /* rows: force x, force y, moment / r_PC; column i: leg i */
  for (int i = 0; i < 3; ++i) {
    const double cx = m->platform_radius * d->link[i].cc, cy = m->platform_radius * d->link[i].sc;
    double ux = q[F3R_Q_X] + cx - m->base_joint[i][0], uy = q[F3R_Q_Y] + cy - m->base_joint[i][1];
    const double len = hypot(ux, uy);
    ux /= len;
    uy /= len;
    J[0][i] = ux;
    J[1][i] = uy;
    J[2][i] = (cx * uy - cy * ux) / m->platform_radius;
  }
  double JtJ[3][3], ev[3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      JtJ[i][j] = J[0][i] * J[0][j] + J[1][i] * J[1][j] + J[2][i] * J[2][j];
  symmetric_eigenvalues3((const double(*)[3])JtJ, ev); /* ISO C before C2X: no implicit const */
  /* sigma_min from the determinant, which stays accurate where the smallest eigenvalue of J^T J
   * drowns in rounding: sigma_1 sigma_2 sigma_3 = |det J|. */
  const double det = J[0][0] * (J[1][1] * J[2][2] - J[1][2] * J[2][1]) -
                     J[0][1] * (J[1][0] * J[2][2] - J[1][2] * J[2][0]) +
                     J[0][2] * (J[1][0] * J[2][1] - J[1][1] * J[2][0]);
  const double sigma_max = sqrt(fmax(ev[2], 0.0)), sigma_mid = sqrt(fmax(ev[1], 0.0));
  const double cond = sigma_max * sigma_max * sigma_mid / fabs(det);
  return isfinite(cond) ? fmin(1e16, cond) : 1e16;
}

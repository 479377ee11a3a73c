#include "independent_lagrangian.h"

#include <complex.h>
#include <math.h>
#include <string.h>

#include "flex3rpr/beam_modes.h" /* f3r_gauss_legendre */
#include "beam_basis.h"          /* f3r_beam_basis_eval */

#define PANELS 24
#define POINTS 8

static double nodes[PANELS * POINTS], weights[PANELS * POINTS];
static int rule_ready = 0;

static void make_rule(void) {
  if (rule_ready) return;
  double x[POINTS], w[POINTS];
  f3r_gauss_legendre(POINTS, x, w);
  for (int p = 0; p < PANELS; ++p)
    for (int k = 0; k < POINTS; ++k) {
      nodes[p * POINTS + k] = (p + x[k]) / PANELS;
      weights[p * POINTS + k] = w[k] / PANELS;
    }
  rule_ready = 1;
}

/* Deflection w(xi) and its rate at xi for link i. */
static void deflection(const f3r_model* m, int i, const double* q, const double* qd, double xi,
                       double* w, double* wd, double* wxx) {
  const f3r_link_params* lp = &m->link[i];
  *w = 0.0;
  if (wd) *wd = 0.0;
  if (wxx) *wxx = 0.0;
  for (int j = 0; j < lp->modes; ++j) {
    double psi, ddpsi;
    /* the paper's modes (f3r_beam_mode_eval) for j < r, the static shapes' closed forms after */
    f3r_beam_basis_eval(&m->basis[i], j, xi, &psi, NULL, &ddpsi);
    *w += psi * q[lp->eta_index + j];
    if (wd) *wd += psi * qd[lp->eta_index + j];
    if (wxx) *wxx += ddpsi * q[lp->eta_index + j] / (m->link_length * m->link_length);
  }
}

/* Beam point position at xi for complex-perturbed coordinates q + i h qd. */
static void position_complex(const f3r_model* m, int i, const double* q, const double* qd, double h,
                             double xi, double complex out[2]) {
  const double l = m->link_length;
  const double complex rho = q[i] + I * h * qd[i];
  const double complex th = q[3 + i] + I * h * qd[3 + i];
  double w_re, w_im;
  deflection(m, i, q, qd, xi, &w_re, &w_im, NULL);
  const double complex w = w_re + I * h * w_im;
  out[0] = m->base_joint[i][0] + (rho + xi * l) * ccos(th) - w * csin(th);
  out[1] = m->base_joint[i][1] + (rho + xi * l) * csin(th) + w * ccos(th);
}

double indep_kinetic_energy(const f3r_model* m, const double* q, const double* qd) {
  make_rule();
  const double l = m->link_length, rho_a = m->link_mass / l;
  double T = 0.5 * m->platform_mass * (qd[6] * qd[6] + qd[7] * qd[7]) +
             0.5 * m->platform_inertia * qd[8] * qd[8];
  for (int i = 0; i < 3; ++i) {
    T += 0.5 * m->cylinder_inertia * qd[3 + i] * qd[3 + i];
    double integral = 0.0;
    for (int k = 0; k < PANELS * POINTS; ++k) {
      const double xi = nodes[k];
      double speed_sq;
      if (m->exact_kinematics) {
        const double h = 1e-20;
        double complex r[2];
        position_complex(m, i, q, qd, h, xi, r);
        const double vx = cimag(r[0]) / h, vy = cimag(r[1]) / h;
        speed_sq = vx * vx + vy * vy;
      } else { /* eq. (9): rho_dot^2 + ((x + rho) theta_dot + w_dot)^2 */
        double w, wd;
        deflection(m, i, q, qd, xi, &w, &wd, NULL);
        const double across = (xi * l + q[i]) * qd[3 + i] + wd;
        speed_sq = qd[i] * qd[i] + across * across;
      }
      integral += weights[k] * speed_sq * l;
    }
    T += 0.5 * rho_a * integral;
  }
  return T;
}

double indep_potential_energy(const f3r_model* m, const double* q) {
  make_rule();
  double V = 0.0;
  for (int i = 0; i < 3; ++i) {
    if (!m->link[i].modes) continue;
    double integral = 0.0;
    for (int k = 0; k < PANELS * POINTS; ++k) {
      double w, wxx;
      deflection(m, i, q, q, nodes[k], &w, NULL, &wxx);
      integral += weights[k] * wxx * wxx * m->link_length;
    }
    V += 0.5 * m->bending_stiffness * integral;
  }
  return V;
}

/* dT/dqd_j: T is quadratic in qd, so a central difference with a unit step is exact. */
static double momentum(const f3r_model* m, const double* q, const double* qd, int j) {
  double plus[F3R_MAX_Q], minus[F3R_MAX_Q];
  memcpy(plus, qd, sizeof plus);
  memcpy(minus, qd, sizeof minus);
  plus[j] += 1.0;
  minus[j] -= 1.0;
  return (indep_kinetic_energy(m, q, plus) - indep_kinetic_energy(m, q, minus)) / 2.0;
}

void indep_lagrange(const f3r_model* m, const double* q, const double* qd, const double* qdd,
                    double* out) {
  const int n = m->nq;
  const double dt = 1e-5;
  double qa[F3R_MAX_Q], qb[F3R_MAX_Q], va[F3R_MAX_Q], vb[F3R_MAX_Q];
  for (int k = 0; k < n; ++k) {
    qa[k] = q[k] + dt * qd[k];
    qb[k] = q[k] - dt * qd[k];
    va[k] = qd[k] + dt * qdd[k];
    vb[k] = qd[k] - dt * qdd[k];
  }
  for (int j = 0; j < n; ++j) {
    const double dpdt = (momentum(m, qa, va, j) - momentum(m, qb, vb, j)) / (2.0 * dt);
    const double step = j >= 9 ? 1e-7 : 1e-6;
    double qp[F3R_MAX_Q], qm[F3R_MAX_Q];
    memcpy(qp, q, sizeof qp);
    memcpy(qm, q, sizeof qm);
    qp[j] += step;
    qm[j] -= step;
    const double dTdq =
        (indep_kinetic_energy(m, qp, qd) - indep_kinetic_energy(m, qm, qd)) / (2 * step);
    const double dVdq =
        (indep_potential_energy(m, qp) - indep_potential_energy(m, qm)) / (2 * step);
    out[j] = dpdt - dTdq + dVdq;
  }
}

double indep_gravity_potential(const f3r_model* m, const double* q) {
  make_rule();
  const double* g = m->gravity;
  const double zero[F3R_MAX_Q] = {0};
  double V = -m->platform_mass * (g[0] * q[6] + g[1] * q[7]);
  for (int i = 0; i < 3; ++i) {
    const double c = cos(q[3 + i]), s = sin(q[3 + i]);
    const double half = m->cylinder_length / 2.0;
    V -= m->cylinder_mass *
         (g[0] * (m->base_joint[i][0] + half * c) + g[1] * (m->base_joint[i][1] + half * s));
    double integral = 0.0;
    for (int k = 0; k < PANELS * POINTS; ++k) {
      double complex r[2];
      position_complex(m, i, q, zero, 0.0, nodes[k], r);
      integral += weights[k] * (g[0] * creal(r[0]) + g[1] * creal(r[1]));
    }
    V -= m->link_mass * integral;
  }
  return V;
}

void indep_constraints(const f3r_model* m, const double* q, double* g) {
  for (int i = 0; i < 3; ++i) {
    double complex tip[2];
    const double zero[F3R_MAX_Q] = {0};
    position_complex(m, i, q, zero, 0.0, 1.0, tip);
    const double angle = m->platform_angle[i] + q[8];
    g[2 * i] = creal(tip[0]) - (q[6] + m->platform_radius * cos(angle));
    g[2 * i + 1] = creal(tip[1]) - (q[7] + m->platform_radius * sin(angle));
  }
}

/* The minimal-coordinate residual and right-hand side: independent z = (X_p, Y_p, phi_p, eta),
 * with rho and theta from the closed-form loop closure. Layout and equations: residual.h; the
 * reduced equations come from the closed acceleration stage (equations.c). */
#include <math.h>
#include <string.h>

#include "dense.h"
#include "form_minimal.h"

void f3r_minimal_rows(const f3r_model* m, const double* y, const double* yp, const f3r_data* d,
                      double* res) {
  const int nz = m->n_independent;
  const int lag_at = m->lag_index[F3R_FORMULATION_MINIMAL], w_at = lag_at + m->n_lag;
  for (int j = 0; j < nz; ++j) res[j] = yp[j] - y[nz + j];
  /* res[nz .. 2 nz): the closed acceleration stage wrote the reduced equations there */
  for (int i = 0; i < m->n_lag; ++i)
    res[lag_at + i] = m->lag_time_constant * yp[lag_at + i] - (d->commanded[i] - y[lag_at + i]);
  res[w_at] = yp[w_at] - d->power;
}

/* The reduced mass K = B^T M B, B = dq/dz, in its arrow blocks at the position stage in
 * ws->data. The dependent coordinates of link i, d_i = (rho_i, theta_i), move with the platform
 * and with link i's own modes only: B's rows d_i are B_iP (2 x 3) on the pose and B_ie (2 x r_i)
 * on eta_i, G_d^{-1} applied to -G_z's columns (-G_P = I on X, Y; -g_phi on phi_p; -psi_j(1) n on
 * eta_j of a fixed-free link). With link i's mass blocks M_dd (2 x 2), M_de = (0; m_theta_eta)
 * and M_ee = m I, K adds per link
 *   K_PP += B_iP^T M_dd B_iP,   K_Pe_i = B_iP^T (M_dd B_ie + M_de),
 *   K_ee_i = B_ie^T M_dd B_ie + B_ie^T M_de + M_de^T B_ie + m I,
 * to the platform's diag(m_p, m_p, I_p), and nothing couples two links' modes. */
/* Link i's rows of B on the pose, B_iP = G_d^{-1} V for V = (1, 0), (0, 1), -g_phi (theta' =
 * n.V / L, rho' = e.V + w theta'), M_dd B_iP, and B_iP^T M_dd B_iP added into K_PP (3 x 3). */
static void pose_rows(const f3r_model* m, const f3r_link_data* k, double bp[2][3], double mbp[2][3],
                      double* kpp) {
  const double V[3][2] = {{1.0, 0.0}, {0.0, 1.0}, {-k->g_phi[0], -k->g_phi[1]}};
  for (int c = 0; c < 3; ++c) {
    bp[1][c] = (-k->s * V[c][0] + k->c * V[c][1]) / k->len;
    bp[0][c] = k->c * V[c][0] + k->s * V[c][1] + k->w * bp[1][c];
  }
  for (int c = 0; c < 3; ++c) {
    mbp[0][c] = m->link_mass * bp[0][c] + k->m_rho_theta * bp[1][c];
    mbp[1][c] = k->m_rho_theta * bp[0][c] + k->m_theta_theta * bp[1][c];
  }
  for (int c = 0; c < 3; ++c)
    for (int e = 0; e < 3; ++e) kpp[c + 3 * e] += bp[0][c] * mbp[0][e] + bp[1][c] * mbp[1][e];
}

/* K_PP's platform part, diag(m_p, m_p, I_p). */
static void platform_mass(const f3r_model* m, double* kpp) {
  for (int z = 0; z < 9; ++z) kpp[z] = 0.0;
  kpp[0] = kpp[4] = m->platform_mass;
  kpp[8] = m->platform_inertia;
}

void f3r_minimal_reduced_mass_blocks(const f3r_model* m, f3r_workspace* ws) {
  const f3r_data* d = &ws->data;
  const double mass = m->link_mass;
  double* kpp = ws->mass_pp;
  platform_mass(m, kpp);
  for (int i = 0; i < 3; ++i) {
    const f3r_link_data* k = &d->link[i];
    const f3r_link_params* lp = &m->link[i];
    const int r = lp->modes, tip = lp->model == F3R_LINK_FIXED_FREE;
    double bp[2][3], mbp[2][3];
    pose_rows(m, k, bp, mbp, kpp);
    if (!r) continue;
    /* B_ie: V = -psi_j(1) n gives theta' = -psi_j(1) / L, rho' = w theta' (0 when fixed-pinned) */
    double be[2][F3R_MAX_MODES], mbe[2][F3R_MAX_MODES];
    for (int j = 0; j < r; ++j) {
      be[1][j] = tip ? -lp->tip[j] / k->len : 0.0;
      be[0][j] = k->w * be[1][j];
      /* M_dd B_ie + M_de */
      mbe[0][j] = mass * be[0][j] + k->m_rho_theta * be[1][j];
      mbe[1][j] = k->m_rho_theta * be[0][j] + k->m_theta_theta * be[1][j] + k->m_theta_eta[j];
    }
    double* kpe = ws->mass_pe[i]; /* 3 x r, column-major */
    double* kee = ws->mass_ee[i]; /* r x r, column-major */
    for (int j = 0; j < r; ++j) {
      for (int c = 0; c < 3; ++c) kpe[c + 3 * j] = bp[0][c] * mbe[0][j] + bp[1][c] * mbe[1][j];
      for (int l = 0; l < r; ++l)
        kee[l + r * j] = be[0][l] * mbe[0][j] + be[1][l] * mbe[1][j] +
                         be[1][j] * k->m_theta_eta[l] + (l == j ? mass : 0.0);
    }
  }
}

/* z index of link i's first modal coordinate. */
static int modal_z(const f3r_model* m, int i) { return m->link[i].eta_index - F3R_Q_INDEPENDENT; }

/* K (nz x nz, leading dimension ld) from its blocks, scaled, added into A. */
void f3r_minimal_add_reduced_mass(const f3r_model* m, const f3r_workspace* ws, double scale,
                                  double* A, int ld) {
  for (int e = 0; e < 3; ++e)
    for (int c = 0; c < 3; ++c) F3R_AT(A, ld, c, e) += scale * ws->mass_pp[c + 3 * e];
  for (int i = 0; i < 3; ++i) {
    const int r = m->link[i].modes, z = modal_z(m, i);
    for (int j = 0; j < r; ++j) {
      for (int c = 0; c < 3; ++c) {
        F3R_AT(A, ld, c, z + j) += scale * ws->mass_pe[i][c + 3 * j];
        F3R_AT(A, ld, z + j, c) += scale * ws->mass_pe[i][c + 3 * j];
      }
      for (int l = 0; l < r; ++l) F3R_AT(A, ld, z + l, z + j) += scale * ws->mass_ee[i][l + r * j];
    }
  }
}

/* Link i's share of K in low-rank form. B_ie = u b^T is of rank one (u = (w, 1), b_j =
 * -psi_j(1) / L, zero for a fixed-pinned link) and M_de = (0; c^T) with c = m_theta_eta, so
 *   K_ee_i = m I + W S W^T,  W = [b c] (r x 2),  S = [mu 1; 1 0],  mu = u^T M_dd u,
 *   K_Pe_i = P W^T,          P = [B_iP^T M_dd u | B_iP^T e_theta] (3 x 2),
 * and by Woodbury K_ee^{-1} y = (y - W T W^T y / m) / m with T = (S^{-1} + W^T W / m)^{-1}. */
typedef struct {
  double b[F3R_MAX_MODES], c[F3R_MAX_MODES];
  double P[3][2];    /* P[pose][column] */
  double G[4], T[4]; /* W^T W and T, 2 x 2 row-major */
  double E[4];       /* (I - T G / m) / m, so that K_ee^{-1} W = W E */
} link_low_rank;

static double dot(const double* x, const double* y, int n) {
  double s = 0.0;
  for (int j = 0; j < n; ++j) s += x[j] * y[j];
  return s;
}

/* Link i's W, P, G, T and E at the position stage; K_PP's share added into kpp. */
static f3r_status link_low_rank_form(const f3r_model* m, const f3r_link_data* k,
                                     const f3r_link_params* lp, double* kpp, link_low_rank* o) {
  const double mass = m->link_mass, inv_mass = 1.0 / mass;
  const int r = lp->modes;
  double bp[2][3], mbp[2][3];
  pose_rows(m, k, bp, mbp, kpp);
  if (!r) return F3R_OK;
  const double tip_scale = lp->model == F3R_LINK_FIXED_FREE ? -1.0 / k->len : 0.0;
  for (int j = 0; j < r; ++j) {
    o->b[j] = tip_scale * lp->tip[j];
    o->c[j] = k->m_theta_eta[j];
  }
  for (int p = 0; p < 3; ++p) {
    o->P[p][0] = mbp[0][p] * k->w + mbp[1][p]; /* (M_dd B_iP)^T u, M_dd symmetric */
    o->P[p][1] = bp[1][p];
  }
  const double mu = mass * k->w * k->w + 2.0 * k->m_rho_theta * k->w + k->m_theta_theta;
  double* G = o->G;
  G[0] = dot(o->b, o->b, r);
  G[1] = G[2] = dot(o->b, o->c, r);
  G[3] = dot(o->c, o->c, r);
  /* N = S^{-1} + G / m with S^{-1} = [0 1; 1 -mu]; T = N^{-1} */
  const double n00 = G[0] * inv_mass, n01 = 1.0 + G[1] * inv_mass, n11 = G[3] * inv_mass - mu;
  const double det = n00 * n11 - n01 * n01;
  if (!(fabs(det) > 0.0)) return F3R_ERR_SINGULAR;
  const double inv_det = 1.0 / det;
  o->T[0] = n11 * inv_det, o->T[3] = n00 * inv_det, o->T[1] = o->T[2] = -n01 * inv_det;
  for (int a = 0; a < 2; ++a)
    for (int e = 0; e < 2; ++e)
      o->E[2 * a + e] =
          ((a == e) - (o->T[2 * a] * G[e] + o->T[2 * a + 1] * G[2 + e]) * inv_mass) * inv_mass;
  return F3R_OK;
}

/* x = S^{-1} x for a symmetric positive definite 3 x 3 S (column-major), by S = L D L^T written
 * out: no square roots, one division a pivot. Returns -1 when a pivot is not positive. */
static int solve_spd3(const double* S, double* x) {
  const double d0 = S[0];
  if (!(d0 > 0.0)) return -1;
  const double l10 = S[1] / d0, l20 = S[2] / d0;
  const double d1 = S[4] - l10 * S[1];
  if (!(d1 > 0.0)) return -1;
  const double l21 = (S[5] - l20 * S[1]) / d1;
  const double d2 = S[8] - l20 * S[2] - l21 * (S[5] - l20 * S[1]);
  if (!(d2 > 0.0)) return -1;
  const double y1 = x[1] - l10 * x[0], y2 = x[2] - l20 * x[0] - l21 * y1;
  x[2] = y2 / d2;
  x[1] = y1 / d1 - l21 * x[2];
  x[0] = x[0] / d0 - l10 * x[1] - l20 * x[2];
  return 0;
}

/* Solves K x = f (f overwritten) without forming K: each link's modes by Woodbury, the pose
 * from the 3 x 3 Schur complement S = K_PP - sum P H P^T (H = W^T K_ee^{-1} W = G E), then the
 * modes x_e = K_ee^{-1} f_e - W E P^T x_P. O(r) a link, against O(r^3) for K's blocks. */
static f3r_status low_rank_solve(const f3r_model* m, const f3r_data* d, double* f) {
  const double inv_mass = 1.0 / m->link_mass;
  double S[9];
  link_low_rank lr[3];
  platform_mass(m, S);
  for (int i = 0; i < 3; ++i) {
    const int r = m->link[i].modes;
    link_low_rank* o = &lr[i];
    if (link_low_rank_form(m, &d->link[i], &m->link[i], S, o) != F3R_OK) return F3R_ERR_SINGULAR;
    if (!r) continue;
    double* y = f + modal_z(m, i); /* y <- K_ee^{-1} y = (y - W T W^T y / m) / m */
    const double wy[2] = {dot(o->b, y, r), dot(o->c, y, r)};
    const double tw[2] = {(o->T[0] * wy[0] + o->T[1] * wy[1]) * inv_mass,
                          (o->T[2] * wy[0] + o->T[3] * wy[1]) * inv_mass};
    for (int j = 0; j < r; ++j) y[j] = (y[j] - o->b[j] * tw[0] - o->c[j] * tw[1]) * inv_mass;
    /* W^T K_ee^{-1} y = (W^T y - G T W^T y / m) / m, and H = G E */
    const double wk[2] = {(wy[0] - o->G[0] * tw[0] - o->G[1] * tw[1]) * inv_mass,
                          (wy[1] - o->G[2] * tw[0] - o->G[3] * tw[1]) * inv_mass};
    double H[4];
    for (int a = 0; a < 2; ++a)
      for (int e = 0; e < 2; ++e)
        H[2 * a + e] = o->G[2 * a] * o->E[e] + o->G[2 * a + 1] * o->E[2 + e];
    for (int p = 0; p < 3; ++p) {
      f[p] -= o->P[p][0] * wk[0] + o->P[p][1] * wk[1];
      const double hp[2] = {H[0] * o->P[p][0] + H[2] * o->P[p][1],
                            H[1] * o->P[p][0] + H[3] * o->P[p][1]}; /* (P H)[p], H symmetric */
      for (int q = 0; q < 3; ++q) S[p + 3 * q] -= hp[0] * o->P[q][0] + hp[1] * o->P[q][1];
    }
  }
  if (solve_spd3(S, f)) return F3R_ERR_SINGULAR;
  for (int i = 0; i < 3; ++i) {
    const link_low_rank* o = &lr[i];
    const int r = m->link[i].modes;
    if (!r) continue;
    double h[2], g[2];
    for (int a = 0; a < 2; ++a) h[a] = o->P[0][a] * f[0] + o->P[1][a] * f[1] + o->P[2][a] * f[2];
    for (int a = 0; a < 2; ++a) g[a] = o->E[2 * a] * h[0] + o->E[2 * a + 1] * h[1];
    double* x = f + modal_z(m, i);
    for (int j = 0; j < r; ++j) x[j] -= o->b[j] * g[0] + o->c[j] * g[1];
  }
  return F3R_OK;
}

/* y' of the minimal formulation. F_u is linear in u': F_u(u') = F_u(0) + K u', F_u(0) the
 * reduced equations of the closed acceleration stage at u' = 0 (the residual's z rows are not
 * needed); likewise the lag and W rows. The solve uses K's low-rank structure (low_rank_solve);
 * dense assembles K whole and factors it (the benchmark's and the tests' comparison). */
f3r_status f3r_minimal_rhs(const f3r_model* m, int structured, const double* y, double* ydot,
                           f3r_workspace* ws) {
  const int nz = m->n_independent, ny = m->state_size[F3R_FORMULATION_MINIMAL];
  const f3r_data* d = &ws->data;
  double* rate = ydot + nz;
  for (int i = 0; i < nz; ++i) rate[i] = -rate[i]; /* the stage wrote F_u(0) there */
  if (!structured) {
    f3r_minimal_reduced_mass_blocks(m, ws);
    double* K = ws->solve_work; /* nz x nz fits in the (nq + 6)^2 of the acceleration solver */
    memset(K, 0, (size_t)nz * (size_t)nz * sizeof(double));
    f3r_minimal_add_reduced_mass(m, ws, 1.0, K, nz);
    double inv[F3R_MAX_Q]; /* 1 / L_jj: multiplications, not divisions */
    if (f3r_cholesky_factor_inv(K, nz, inv)) return F3R_ERR_SINGULAR; /* K is positive definite */
    f3r_cholesky_solve_inv(K, nz, inv, rate, 1);
  } else if (low_rank_solve(m, d, rate) != F3R_OK) {
    return F3R_ERR_SINGULAR;
  }
  for (int i = 0; i < nz; ++i) ydot[i] = y[nz + i];
  const int lag_at = 2 * nz;
  for (int i = 0; i < m->n_lag; ++i) { /* F_lag(F_a' = 0), as the residual forms it */
    const double res = m->lag_time_constant * 0.0 - (d->commanded[i] - y[lag_at + i]);
    ydot[lag_at + i] = -res / m->lag_time_constant;
  }
  ydot[ny - 1] = -(0.0 - d->power); /* F_W(W' = 0) = -Q.v */
  return F3R_OK;
}

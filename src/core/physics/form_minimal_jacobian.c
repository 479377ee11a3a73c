/* The analytic Jacobian of the minimal residual (form_minimal.c): the loop closure's B = dq/dz and
 * its rates, applied to the per-link blocks of the force and constraint derivatives. The equations
 * are at f3r_minimal_jacobian, at the end. */
#include <string.h>

#include "dense.h"
#include "derivatives.h"
#include "effects.h"
#include "form_minimal.h"

/* The links a column of B reaches: every link for the pose (owner -1), its own for a modal one. */
static void links_of_column(int owner, int* first, int* end) {
  *first = owner < 0 ? 0 : owner;
  *end = owner < 0 ? 3 : owner + 1;
}

/* Link l's rows (rho_l, theta_l, eta_l). The nq x nq products Z and H (and the effects' dQ/dq,
 * dQ/dv) couple each link's coordinates only among themselves, and the platform's among
 * themselves (the terms of derivatives.c and effects.c; test_residual_jacobian checks
 * the result against finite differences). So column rho_l or theta_l of X reaches these rows
 * only, and a modal column of link l (whose B column moves link l's legs alone) too. */
typedef struct {
  int n;                      /* 2 + r */
  int rho, theta;             /* q indices of the legs */
  int row[2 + F3R_MAX_MODES]; /* q index of each row: rho, theta, then the modes */
} link_rows;

static void links_rows(const f3r_model* m, link_rows rows[3]) {
  for (int l = 0; l < 3; ++l) {
    link_rows* s = &rows[l];
    s->n = 2 + m->link[l].modes, s->rho = l, s->theta = F3R_Q_THETA + l;
    s->row[0] = s->rho, s->row[1] = s->theta;
    for (int e = 0; e < m->link[l].modes; ++e) s->row[2 + e] = m->link[l].eta_index + e;
  }
}

/* Row k of a link's share of a column: o[k] on the link's rows alone (compact), or o[row[k]] in a
 * whole column (nq). */
#define AT(o, s, k, whole) (o)[(whole) ? (s)->row[k] : (k)]

/* o += X(:, legs_l) (br, bt) on link l's rows, row by row in the dense sum's order (the rho_l
 * column's term, then the theta_l column's), only the terms that can be nonzero (a skipped term
 * is an exact zero); both in one pass where both are nonzero, so that each row is loaded and
 * stored once. */
F3R_INLINE void add_link_leg_columns(const double* X, int nq, const link_rows* s, double br,
                                     double bt, double* o, int whole) {
  const double *xr = X + (size_t)nq * s->rho, *xt = X + (size_t)nq * s->theta;
  if (br != 0.0 && bt != 0.0) {
    for (int k = 0; k < s->n; ++k)
      AT(o, s, k, whole) = (AT(o, s, k, whole) + xr[s->row[k]] * br) + xt[s->row[k]] * bt;
    return;
  }
  const double bc = br != 0.0 ? br : bt;
  if (bc == 0.0) return;
  const double* x = br != 0.0 ? xr : xt;
  for (int k = 0; k < s->n; ++k) AT(o, s, k, whole) += x[s->row[k]] * bc;
}

/* o += M x on link l's rows, for x (nq) nonzero on the legs only (as f3r_data_mass_times gives
 * it: the skipped terms are exact zeros). */
F3R_INLINE void add_link_mass_times_legs(const f3r_model* m, const f3r_link_data* k,
                                         const link_rows* s, const double* x, double* o,
                                         int whole) {
  const double xr = x[s->rho], xt = x[s->theta];
  AT(o, s, 0, whole) += m->link_mass * xr + k->m_rho_theta * xt;
  AT(o, s, 1, whole) += k->m_rho_theta * xr + k->m_theta_theta * xt;
  for (int e = 0; e < s->n - 2; ++e) AT(o, s, 2 + e, whole) += k->m_theta_eta[e] * xt;
}

/* A pose column, whole: o += X(:, legs) b, link by link (the other legs' columns do not reach a
 * link's rows). */
static void add_leg_columns(const link_rows rows[3], int nq, const double* X, const double* b,
                            double* o) {
  for (int i = 0; i < 3; ++i) add_link_leg_columns(X, nq, &rows[i], b[i], b[F3R_Q_THETA + i], o, 1);
}

/* A pose column, whole: J(rows0.., j) += B^T y (jcol points at J's entry (rows0, j)), B the
 * identity on z below its dependent rows Bd (6 x nz). */
static void add_B_transpose_pose_column(const int* owner, int nz, const double* Bd, const double* y,
                                        double* jcol) {
  for (int i = 0; i < nz; ++i) {
    const int l = owner[i];
    double sum = y[F3R_Q_INDEPENDENT + i];
    if (l < 0) {
      for (int c = 0; c < F3R_Q_LEG_JOINTS; ++c) sum += Bd[c + 6 * i] * y[c];
    } else { /* column z_i of Bd reaches its own link's legs only */
      sum += Bd[l + 6 * i] * y[l];
      sum += Bd[F3R_Q_THETA + l + 6 * i] * y[F3R_Q_THETA + l];
    }
    jcol[i] += sum;
  }
}

/* owner[j]: the link whose modal coordinate z_j is, or -1 for the pose. */
static void column_owners(const f3r_model* m, int* owner) {
  for (int j = 0; j < 3; ++j) owner[j] = -1;
  for (int l = 0; l < 3; ++l)
    for (int e = 0; e < m->link[l].modes; ++e)
      owner[m->link[l].eta_index - F3R_Q_INDEPENDENT + e] = l;
}

/* The Jacobian's products, column-major, in ws->jac_work (cleared per evaluation) and ws->dQ. */
typedef struct {
  double* Z;   /* nq x nq: d(M a)/dq + dh/dq + dk/dq - dQ/dq - d(G^T lambda)/dq */
  double* H;   /* nq x nq: dh/dv - dQ/dv */
  double* Gvq; /* 6 x nq: d(G v)/dq */
  double* Caq; /* 6 x nq: d(G a)/dq + dgamma/dq */
  double* gv;  /* 6 x nq: dgamma/dv */
  double* Bd;  /* 6 x nz: B's dependent rows */
  double* Vz;  /* nq x nz */
  double* Az;  /* nq x nz */
  double* Au;  /* nq x nz */
  double* Qq;  /* nq x nq: dQ/dq */
  double* Qv;  /* nq x nq: dQ/dv */
} jacobian_products;

static jacobian_products jacobian_products_in(f3r_workspace* ws, int nq, int nz) {
  jacobian_products p;
  p.Z = ws->jac_work;
  p.H = p.Z + (size_t)nq * nq;
  p.Gvq = p.H + (size_t)nq * nq;
  p.Caq = p.Gvq + 6 * nq;
  p.gv = p.Caq + 6 * nq;
  p.Bd = p.gv + 6 * nq;
  p.Vz = p.Bd + 6 * nz;
  p.Az = p.Vz + (size_t)nq * nz;
  p.Au = p.Az + (size_t)nq * nz;
  p.Qq = ws->dQ;
  p.Qv = ws->dQ + (size_t)nq * nq;
  return p;
}

/* Z and H are nonzero only in the links' blocks and at (phi_p, phi_p) (add_leg_columns): only
 * those are cleared per evaluation; the rest was cleared when the workspace was created, and
 * nothing writes it (the effects' dQ is zero there too). */
static void clear_link_blocks(const f3r_model* m, double* X) {
  const int nq = m->nq;
  for (int i = 0; i < 3; ++i) {
    const int base = m->link[i].eta_index, modes = m->link[i].modes;
    const int cols[2] = {i, F3R_Q_THETA + i};
    for (int n = 0; n < 2 + modes; ++n) { /* the link's columns: rho_i, theta_i, then its modes */
      double* x = X + (size_t)nq * (n < 2 ? cols[n] : base + n - 2);
      x[i] = 0.0;
      x[F3R_Q_THETA + i] = 0.0;
      memset(x + base, 0, (size_t)modes * sizeof(double));
    }
  }
  X[F3R_Q_PHI + (size_t)nq * F3R_Q_PHI] = 0.0;
}

/* Z, H, dQ/dq, dQ/dv and the constraints' derivatives at the state the residual left in ws,
 * with the loop forces lambda held. */
static void force_derivatives(const f3r_model* m, f3r_workspace* ws, const jacobian_products* p) {
  const int nq = m->nq;
  const f3r_data* d = &ws->data;
  const double *q = d->q, *v = d->v, *a = d->a;
  double *Z = p->Z, *H = p->H, *Qq = p->Qq, *Qv = p->Qv;
  clear_link_blocks(m, Z);
  clear_link_blocks(m, H);
  memset(p->Gvq, 0, 18 * (size_t)nq * sizeof(double)); /* Gvq, Caq, gv */
  const int effects = f3r_effects_have_derivatives(m);
  if (effects) {
    memset(ws->dQ, 0, 2 * (size_t)nq * nq * sizeof(double));
    f3r_effects_add_derivatives(m, d, 1.0, Qq, Qv, nq);
  }
  f3r_add_mass_times_dq(m, q, a, 1.0, Z, nq);
  f3r_add_velocity_forces_dq(m, q, v, 1.0, Z, nq);
  f3r_add_elastic_forces_dq(m, 1.0, Z, nq);
  f3r_data_add_constraint_transpose_times_dq(m, d, d->lambda, -1.0, Z, nq);
  f3r_data_add_velocity_forces_dv(m, d, q, 1.0, H, nq);
  if (effects)
    for (size_t k = 0; k < (size_t)nq * nq; ++k) Z[k] -= Qq[k], H[k] -= Qv[k];
  f3r_data_add_constraint_times_dq(m, d, v, 1.0, p->Gvq, 6);
  f3r_data_add_constraint_times_dq(m, d, a, 1.0, p->Caq, 6);
  f3r_data_add_constraint_bias_dq(m, d, v, 1.0, p->Caq, 6);
  f3r_data_add_constraint_bias_dv(m, d, v, 1.0, p->gv, 6);
}

/* Link i's rows of -G's column z_j, as f3r_data_add_constraint_jacobian(-1) adds them into a
 * cleared G (0.0 + -1.0 * entry; an entry G does not have stays 0.0): -G_P = I on (X, Y), -g_phi
 * on phi_p, -psi_j(1) n (the position stage's g_eta) on a fixed-free link's own modes. */
static void minus_constraint_column(const f3r_model* m, const f3r_link_data* k, int i, int j,
                                    double* vx, double* vy) {
  const f3r_link_params* lp = &m->link[i];
  const int e = j - (lp->eta_index - F3R_Q_INDEPENDENT);
  *vx = *vy = 0.0;
  if (j == F3R_Q_X - F3R_Q_INDEPENDENT) {
    *vx += -1.0 * -1.0;
  } else if (j == F3R_Q_Y - F3R_Q_INDEPENDENT) {
    *vy += -1.0 * -1.0;
  } else if (j == F3R_Q_PHI - F3R_Q_INDEPENDENT) {
    *vx += -1.0 * k->g_phi[0];
    *vy += -1.0 * k->g_phi[1];
  } else if (lp->model == F3R_LINK_FIXED_FREE && e >= 0 && e < lp->modes) {
    *vx += -1.0 * k->g_eta_x[e];
    *vy += -1.0 * k->g_eta_y[e];
  }
}

/* B's dependent rows (6 x nz): G_d^{-1} applied to -G_z's columns, on the links a column
 * reaches (zero on the others). */
static void dependent_rows_of_B(const f3r_model* m, const f3r_data* d, const int* owner, int nz,
                                double* Bd) {
  for (int j = 0; j < nz; ++j) {
    double* b = Bd + 6 * j;
    for (int c = 0; c < F3R_Q_LEG_JOINTS; ++c) b[c] = 0.0;
    int first, end;
    links_of_column(owner[j], &first, &end);
    for (int i = first; i < end; ++i) {
      double vx, vy;
      minus_constraint_column(m, &d->link[i], i, j, &vx, &vy);
      f3r_link_solve_dependent(&d->link[i], vx, vy, &b[i], &b[F3R_Q_THETA + i]);
    }
  }
}

/* Link i's two rows of X B, column j, for X (6 x nq) of the constraints' derivatives: B is the
 * identity on z below its dependent rows Bd (6 x nz), and the rows of link i reach only its own
 * legs' columns rho_i, theta_i, so (X B)(r, j) = X(r, z_j) + X(r, legs_i) Bd(legs_i, j). */
F3R_INLINE void link_rows_times_B(const double* X, const double* Bd, int i, int j, double out[2]) {
  const int t = F3R_Q_THETA + i;
  for (int e = 0; e < 2; ++e) {
    const int r = 2 * i + e;
    double sum = X[r + 6 * (F3R_Q_INDEPENDENT + j)];
    sum += X[r + 6 * i] * Bd[i + 6 * j];
    sum += X[r + 6 * t] * Bd[t + 6 * j];
    out[e] = sum;
  }
}

/* V_z, A_u, A_z: only their legs' rows are nonzero, and a modal column's only on its own link's
 * (the others are -0.0, as -G_d^{-1} 0 gives them). Column by column, link by link:
 *   V_z = -G_d^{-1} d(G v)/dq B,  A_u = -G_d^{-1} dgamma/dv B,
 *   A_z = -G_d^{-1} [(d(G a)/dq + dgamma/dq) B + dgamma/dv V_z]. */
static void dependent_rates(const f3r_data* d, const int* owner, int nq, int nz,
                            const jacobian_products* p) {
  const double *Bd = p->Bd, *gv = p->gv;
  for (int j = 0; j < nz; ++j) {
    double *vz = p->Vz + (size_t)nq * j, *au = p->Au + (size_t)nq * j, *az = p->Az + (size_t)nq * j;
    for (int c = 0; c < F3R_Q_LEG_JOINTS; ++c) vz[c] = au[c] = az[c] = -0.0;
    int first, end;
    links_of_column(owner[j], &first, &end);
    for (int i = first; i < end; ++i) {
      const f3r_link_data* k = &d->link[i];
      const int t = F3R_Q_THETA + i;
      double x[2], rho, theta;
      link_rows_times_B(p->Gvq, Bd, i, j, x);
      f3r_link_solve_dependent(k, x[0], x[1], &rho, &theta);
      const double vr = -rho, vt = -theta; /* V_z's, kept for A_z (not reloaded from vz) */
      vz[i] = vr, vz[t] = vt;
      link_rows_times_B(gv, Bd, i, j, x);
      f3r_link_solve_dependent(k, x[0], x[1], &rho, &theta);
      au[i] = -rho, au[t] = -theta;
      link_rows_times_B(p->Caq, Bd, i, j, x);
      for (int e = 0; e < 2; ++e) { /* + dgamma/dv V_z: link i's rows reach its own legs only */
        x[e] += gv[2 * i + e + 6 * i] * vr;
        x[e] += gv[2 * i + e + 6 * t] * vt;
      }
      f3r_link_solve_dependent(k, x[0], x[1], &rho, &theta);
      az[i] = -rho, az[t] = -theta;
    }
  }
}

/* A modal column of link l, y on link l's rows alone (compact; zero elsewhere): y += M x, then
 * J's column += B^T y: on the pose's rows through Bd's pose columns, on link l's modes through
 * theirs (the other links' modal rows stay zero). */
F3R_INLINE void add_modal_column(const f3r_model* m, const f3r_link_data* k, const link_rows* s,
                                 const double* Bd, const double* x, double* y, double* jcol) {
  add_link_mass_times_legs(m, k, s, x, y, 0);
  for (int i = 0; i < 3; ++i) {
    double sum = 0.0 + Bd[s->rho + 6 * i] * y[0];
    jcol[i] += sum + Bd[s->theta + 6 * i] * y[1];
  }
  const int z0 = s->row[2] - F3R_Q_INDEPENDENT;
  for (int e = 0; e < s->n - 2; ++e) {
    const int i = z0 + e;
    double sum = y[2 + e] + Bd[s->rho + 6 * i] * y[0];
    jcol[i] += sum + Bd[s->theta + 6 * i] * y[1];
  }
}

/* Both of J's columns of modal coordinate z_j of link l, on link l's rows alone. */
static void add_modal_force_columns(const f3r_model* m, const f3r_data* d, const link_rows* s,
                                    const jacobian_products* p, int j, double* jz, double* ju) {
  const int nq = m->nq;
  const size_t col = (size_t)nq * (F3R_Q_INDEPENDENT + j);
  const double *bd = p->Bd + 6 * j, *vz = p->Vz + (size_t)nq * j;
  double y[2 + F3R_MAX_MODES];
  for (int k = 0; k < s->n; ++k) y[k] = p->Z[col + s->row[k]];
  add_link_leg_columns(p->Z, nq, s, bd[s->rho], bd[s->theta], y, 0);
  add_link_leg_columns(p->H, nq, s, vz[s->rho], vz[s->theta], y, 0);
  add_modal_column(m, &d->link[s->rho], s, p->Bd, p->Az + (size_t)nq * j, y, jz);
  for (int k = 0; k < s->n; ++k) y[k] = p->H[col + s->row[k]];
  add_link_leg_columns(p->H, nq, s, bd[s->rho], bd[s->theta], y, 0);
  add_modal_column(m, &d->link[s->rho], s, p->Bd, p->Au + (size_t)nq * j, y, ju);
}

/* Both of J's columns of pose coordinate z_j (j < 3), whole. */
static void add_pose_force_columns(const f3r_model* m, const f3r_data* d, const link_rows rows[3],
                                   const int* owner, const jacobian_products* p, int j, double* jz,
                                   double* ju) {
  const int nq = m->nq, nz = m->n_independent;
  const size_t col = (size_t)nq * (F3R_Q_INDEPENDENT + j);
  const double* bd = p->Bd + 6 * j;
  double t[F3R_MAX_Q];
  memcpy(t, p->Z + col, (size_t)nq * sizeof(double));
  add_leg_columns(rows, nq, p->Z, bd, t);
  add_leg_columns(rows, nq, p->H, p->Vz + (size_t)nq * j, t);
  for (int i = 0; i < 3; ++i)
    add_link_mass_times_legs(m, &d->link[i], &rows[i], p->Az + (size_t)nq * j, t, 1);
  add_B_transpose_pose_column(owner, nz, p->Bd, t, jz);
  memcpy(t, p->H + col, (size_t)nq * sizeof(double));
  add_leg_columns(rows, nq, p->H, bd, t);
  for (int i = 0; i < 3; ++i)
    add_link_mass_times_legs(m, &d->link[i], &rows[i], p->Au + (size_t)nq * j, t, 1);
  add_B_transpose_pose_column(owner, nz, p->Bd, t, ju);
}

/* The reduced equations' rows in z and u: dF_u/dz = B^T (Z B + H V_z + M A_z) and
 * dF_u/du = B^T (H B + M A_u), added into J a column j of both at a time; a modal column on its
 * link's rows alone. */
static void add_force_blocks(const f3r_model* m, const f3r_data* d, const int* owner,
                             const jacobian_products* p, double* J, int ld) {
  const int nz = m->n_independent;
  link_rows rows[3];
  links_rows(m, rows);
  for (int j = 0; j < 3; ++j)
    add_pose_force_columns(m, d, rows, owner, p, j, &F3R_AT(J, ld, nz, j),
                           &F3R_AT(J, ld, nz, nz + j));
  for (int l = 0; l < 3; ++l) {
    const int first = m->link[l].eta_index - F3R_Q_INDEPENDENT;
    for (int j = first; j < first + m->link[l].modes; ++j)
      add_modal_force_columns(m, d, &rows[l], p, j, &F3R_AT(J, ld, nz, j),
                              &F3R_AT(J, ld, nz, nz + j));
  }
}

/* cj dF/dy' for z (identity), u (B^T M B) and the lag states (tau, with their own 1), and
 * F_z = z' - u; the lag states enter R_rho with -1 and F_W with -rho'. */
static void add_rate_and_lag_blocks(const f3r_model* m, f3r_workspace* ws, double cj,
                                    const double* Bd, int w_at, double* J, int ld) {
  const int nz = m->n_independent, lag_at = 2 * nz;
  const double* v = ws->data.v;
  for (int j = 0; j < nz; ++j) {
    F3R_AT(J, ld, j, j) += cj;
    F3R_AT(J, ld, j, nz + j) -= 1.0;
  }
  f3r_minimal_reduced_mass_blocks(m, ws);
  f3r_minimal_add_reduced_mass(m, ws, cj, &F3R_AT(J, ld, nz, nz), ld);
  for (int i = 0; i < m->n_lag; ++i) {
    F3R_AT(J, ld, lag_at + i, lag_at + i) += 1.0 + cj * m->lag_time_constant;
    for (int r = 0; r < nz; ++r) F3R_AT(J, ld, nz + r, lag_at + i) -= Bd[F3R_Q_RHO + i + 6 * r];
    F3R_AT(J, ld, w_at, lag_at + i) -= v[F3R_Q_RHO + i];
  }
}

/* The work row F_W = W' - Q . v: dF_W/dz = -(v^T dQ/dq B + (v^T dQ/dv + Q^T) V_z),
 * dF_W/du = -(v^T dQ/dv + Q^T) B, dF_W/dW' = 1. */
static void add_work_row(const f3r_model* m, const f3r_workspace* ws, double cj,
                         const jacobian_products* p, int w_at, double* J, int ld) {
  const int nq = m->nq, nz = m->n_independent;
  const double *v = ws->data.v, *Qq = p->Qq, *Qv = p->Qv, *Bd = p->Bd, *Vz = p->Vz;
  double wq[F3R_MAX_Q], wv[F3R_MAX_Q];                 /* v^T dQ/dq and v^T dQ/dv + Q^T, as rows */
  const int effects = f3r_effects_have_derivatives(m); /* without, dQ/dq and dQ/dv are zero */
  for (int c = 0; c < nq; ++c) {
    double sq = 0.0, sv = ws->data.Q[c];
    if (effects)
      for (int r = 0; r < nq; ++r) sq += v[r] * Qq[r + nq * c], sv += v[r] * Qv[r + nq * c];
    wq[c] = sq, wv[c] = sv;
  }
  for (int j = 0; j < nz; ++j) {
    double dz = wq[F3R_Q_INDEPENDENT + j], du = wv[F3R_Q_INDEPENDENT + j];
    for (int c = 0; c < F3R_Q_LEG_JOINTS; ++c)
      dz += wq[c] * Bd[c + 6 * j] + wv[c] * Vz[c + nq * j], du += wv[c] * Bd[c + 6 * j];
    F3R_AT(J, ld, w_at, j) -= dz;
    F3R_AT(J, ld, w_at, nz + j) -= du;
  }
  F3R_AT(J, ld, w_at, w_at) += cj;
}

/* The analytic Jacobian of the minimal residual. With the loop forces lambda held, the reduced
 * equations vary as dF_u = B^T (dR - d(G^T lambda)/dq dq), R = M a + h + k - Q, and the loop
 * closure gives dq/dz = B, dv/dz = V_z, dv/du = B, da/dz = A_z, da/du = A_u, da/du' = B, whose
 * dependent rows follow from G v = 0 and G a + gamma = 0 (their z rows are zero):
 *   V_z = -G_d^{-1} d(G v)/dq B,
 *   A_z = -G_d^{-1} [(d(G a)/dq + dgamma/dq) B + dgamma/dv V_z],   A_u = -G_d^{-1} dgamma/dv B.
 * Hence, with Z = d(M a)/dq + dh/dq + dk/dq - dQ/dq - d(G^T lambda)/dq and H = dh/dv - dQ/dv,
 *   dF_u/dz = B^T (Z B + H V_z + M A_z),  dF_u/du = B^T (H B + M A_u),  dF_u/du' = B^T M B;
 * the lag states enter R_rho with -1; F_W = W' - Q.v gives dF_W/dz = -(v^T dQ/dq B +
 * (v^T dQ/dv + Q^T) V_z), dF_W/du = -(v^T dQ/dv + Q^T) B, dF_W/dF_a = -rho'. */
void f3r_minimal_jacobian(const f3r_model* m, double cj, double* J, int ld, f3r_workspace* ws) {
  const int nq = m->nq, nz = m->n_independent, ny = m->state_size[F3R_FORMULATION_MINIMAL];
  const int w_at = ny - 1;
  const jacobian_products p = jacobian_products_in(ws, nq, nz);
  force_derivatives(m, ws, &p);
  int owner[F3R_MAX_Q];
  column_owners(m, owner);
  dependent_rows_of_B(m, &ws->data, owner, nz, p.Bd);
  dependent_rates(&ws->data, owner, nq, nz, &p);
  add_force_blocks(m, &ws->data, owner, &p, J, ld);
  add_rate_and_lag_blocks(m, ws, cj, p.Bd, w_at, J, ld);
  add_work_row(m, ws, cj, &p, w_at, J, ld);
}

/* The link basis with static correction shapes (beam_basis.h; issue 28).
 *
 * Numerics (test/reference/static_correction_reference.py and its derivation):
 * - The couplings C_jk = int psi_j s_k are closed forms. Four integrations by parts with
 *   psi_j'''' = alpha_j^4 psi_j, s_k'''' = q0 + q1 xi, s_k''(1) = 0 and, at a free end,
 *   s_k'''(1) = -F give alpha_j^4 C_jk = F tip_j + q0 mean_j + q1 first_moment_j.
 * - The residual Grams M_t = int t_k t_l and K_t = int t_k'' t_l'' come from composite
 *   Gauss-Legendre quadrature of the pointwise residual t_k(xi) = s_k(xi) - sum_j C_jk psi_j(xi),
 *   never from S - C^T C: that subtraction loses eps (|s|/|t|)^2, which is garbage in doubles
 *   at r = 10 (|t|/|s| ~ 1e-6..1e-8); the pointwise residual loses only eps |s|/|t|.
 * - A shape whose residual is below F3R_SHAPE_DROP_RATIO of itself is dropped, and so is the
 *   weakest shape while the unit-diagonal residual Gram has an eigenvalue below 1e-10 (mutual
 *   near-dependence). The rest is a p x p (p <= 3) symmetric-definite eigenproblem: Cholesky of
 *   the scaled M_t, Jacobi on L^-1 K_t L^-T.
 * - The constants of a correction, key(phi_m) = sum_k V_km key(t_k) with key(t_k) = key(s_k) -
 *   sum_j C_jk key(psi_j), use the shapes' exact rational integrals and the modes' closed-form
 *   constants. Their rounding is eps |s|/|t| as with quadrature of t_k (the same cancellation,
 *   summed once instead of per node), without the rule's truncation; the test checks both
 *   against 50-digit values. The fixed-pinned tip is exactly 0. */
#include "beam_basis.h"

#include <math.h>
#include <string.h>

#include "dense.h"

/* As beam_modes.c: 64 panels of 12 points integrate mode 20's boundary layer to rounding. */
#define F3R_BASIS_PANELS 64
#define F3R_BASIS_POINTS 12
/* Second drop guard: the smallest eigenvalue of the unit-diagonal residual Gram. Measured
 * 2e-5 at worst (fixed-free r = 1 with all three shapes), so it only guards degenerate input. */
#define F3R_SHAPE_DEPENDENCE 1e-10

typedef struct {
  unsigned kind;
  double c[6];                          /* s(xi) = sum_a c[a] xi^a */
  double load[3];                       /* tip force F, q0, q1 (s'''' = q0 + q1 xi, s'''(1) = -F) */
  double mean, first_moment, tip, mass; /* int s, int xi s, s(1), int s^2: exact rationals */
} shape_def;

static const shape_def kFreeShapes[3] = {
    {F3R_SHAPE_TIP_FORCE,
     {0, 0, 1.0 / 2, -1.0 / 6, 0, 0},
     {1, 0, 0},
     1.0 / 8,
     11.0 / 120,
     1.0 / 3,
     11.0 / 420},
    {F3R_SHAPE_UNIFORM_LOAD,
     {0, 0, 1.0 / 4, -1.0 / 6, 1.0 / 24, 0},
     {0, 1, 0},
     1.0 / 20,
     13.0 / 360,
     1.0 / 8,
     13.0 / 3240},
    {F3R_SHAPE_LINEAR_LOAD,
     {0, 0, 1.0 / 6, -1.0 / 12, 0, 1.0 / 120},
     {0, 0, 1},
     13.0 / 360,
     11.0 / 420,
     11.0 / 120,
     2641.0 / 1247400},
};
static const shape_def kPinnedShapes[2] = {
    {F3R_SHAPE_UNIFORM_LOAD,
     {0, 0, 1.0 / 16, -5.0 / 48, 1.0 / 24, 0},
     {0, 1, 0},
     1.0 / 320,
     1.0 / 576,
     0,
     19.0 / 1451520},
    {F3R_SHAPE_LINEAR_LOAD,
     {0, 0, 7.0 / 240, -3.0 / 80, 0, 1.0 / 120},
     {0, 0, 1},
     1.0 / 576,
     11.0 / 11200,
     0,
     181.0 / 44352000},
};

static const shape_def* find_shape(f3r_beam_end end, unsigned kind) {
  const shape_def* list = end == F3R_BEAM_FIXED_FREE ? kFreeShapes : kPinnedShapes;
  const int n = end == F3R_BEAM_FIXED_FREE ? 3 : 2;
  for (int k = 0; k < n; ++k)
    if (list[k].kind == kind) return &list[k];
  return NULL;
}

/* s, s', s'' of a shape at xi (Horner). */
static void shape_eval(const shape_def* s, double xi, double* v, double* dv, double* ddv) {
  double p = 0, dp = 0, ddp = 0;
  for (int a = 5; a >= 0; --a) {
    ddp = ddp * xi + dp * 2.0;
    dp = dp * xi + p;
    p = p * xi + s->c[a];
  }
  if (v) *v = p;
  if (dv) *dv = dp;
  if (ddv) *ddv = ddp;
}

/* The work of building: the shapes asked for, in tip, uniform, linear order. */
typedef struct {
  int p;
  const shape_def* shape[3];
  double C[F3R_MAX_MODES][3]; /* int psi_j s_k */
  double Mt[3][3], Kt[3][3];  /* the residuals' Grams */
} build_work;

/* M_t and K_t by composite Gauss-Legendre quadrature of the pointwise residual. */
static void residual_grams(const f3r_beam_basis* b, build_work* w) {
  double x[F3R_BASIS_POINTS], wt[F3R_BASIS_POINTS];
  f3r_gauss_legendre(F3R_BASIS_POINTS, x, wt);
  memset(w->Mt, 0, sizeof w->Mt);
  memset(w->Kt, 0, sizeof w->Kt);
  for (int panel = 0; panel < F3R_BASIS_PANELS; ++panel) {
    double pm[3][3] = {{0}}, pk[3][3] = {{0}}; /* per panel, then added: less rounding */
    for (int q = 0; q < F3R_BASIS_POINTS; ++q) {
      const double xi = (panel + x[q]) / F3R_BASIS_PANELS, wq = wt[q] / F3R_BASIS_PANELS;
      double t[3], tdd[3], psi[F3R_MAX_MODES], dd[F3R_MAX_MODES];
      for (int j = 0; j < b->modes; ++j)
        f3r_beam_mode_eval(b->end, b->alpha[j], xi, &psi[j], NULL, &dd[j]);
      for (int k = 0; k < w->p; ++k) {
        shape_eval(w->shape[k], xi, &t[k], NULL, &tdd[k]);
        for (int j = 0; j < b->modes; ++j) {
          t[k] -= w->C[j][k] * psi[j];
          tdd[k] -= w->C[j][k] * dd[j];
        }
      }
      for (int k = 0; k < w->p; ++k)
        for (int l = 0; l < w->p; ++l) {
          pm[k][l] += wq * t[k] * t[l];
          pk[k][l] += wq * tdd[k] * tdd[l];
        }
    }
    for (int k = 0; k < w->p; ++k)
      for (int l = 0; l < w->p; ++l) {
        w->Mt[k][l] += pm[k][l];
        w->Kt[k][l] += pk[k][l];
      }
  }
}

/* Removes shape k from the work (its coupling column and its Gram rows and columns). */
static void drop_shape(build_work* w, double* ratio, int k) {
  for (int i = k; i + 1 < w->p; ++i) {
    w->shape[i] = w->shape[i + 1];
    ratio[i] = ratio[i + 1];
    for (int j = 0; j < F3R_MAX_MODES; ++j) w->C[j][i] = w->C[j][i + 1];
  }
  for (int i = k; i + 1 < w->p; ++i)
    for (int l = 0; l < w->p; ++l) {
      w->Mt[i][l] = w->Mt[i + 1][l];
      w->Kt[i][l] = w->Kt[i + 1][l];
    }
  for (int i = 0; i < w->p; ++i)
    for (int l = k; l + 1 < w->p; ++l) {
      w->Mt[i][l] = w->Mt[i][l + 1];
      w->Kt[i][l] = w->Kt[i][l + 1];
    }
  --w->p;
}

/* The smallest eigenvalue of the unit-diagonal residual Gram D M_t D. */
static double dependence(const build_work* w) {
  double A[9], eig[3];
  for (int k = 0; k < w->p; ++k)
    for (int l = 0; l < w->p; ++l)
      F3R_AT(A, w->p, k, l) = w->Mt[k][l] / sqrt(w->Mt[k][k] * w->Mt[l][l]);
  f3r_symmetric_eigen(A, w->p, eig, NULL);
  double lo = eig[0];
  for (int k = 1; k < w->p; ++k) lo = fmin(lo, eig[k]);
  return lo;
}

/* The drop tests: residual below F3R_SHAPE_DROP_RATIO of its shape, then the weakest shape
 * while the rest are nearly dependent. ratio[k] receives ||t_k|| / ||s_k||. */
static void drop_weak_shapes(build_work* w, double* ratio) {
  for (int k = 0; k < w->p; ++k) ratio[k] = sqrt(fmax(w->Mt[k][k], 0.0) / w->shape[k]->mass);
  for (int k = w->p - 1; k >= 0; --k)
    if (!(ratio[k] >= F3R_SHAPE_DROP_RATIO)) drop_shape(w, ratio, k);
  while (w->p > 1 && !(dependence(w) >= F3R_SHAPE_DEPENDENCE)) {
    int weakest = 0;
    for (int k = 1; k < w->p; ++k)
      if (ratio[k] < ratio[weakest]) weakest = k;
    drop_shape(w, ratio, weakest);
  }
}

/* Solves L y = b in place (L lower, column-major n x n). */
static void forward_solve(const double* L, int n, double* b) {
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < i; ++k) b[i] -= F3R_AT(L, n, i, k) * b[k];
    b[i] /= F3R_AT(L, n, i, i);
  }
}

/* Solves L^T y = b in place. */
static void backward_solve(const double* L, int n, double* b) {
  for (int i = n - 1; i >= 0; --i) {
    for (int k = i + 1; k < n; ++k) b[i] -= F3R_AT(L, n, k, i) * b[k];
    b[i] /= F3R_AT(L, n, i, i);
  }
}

/* K_t v = lambda M_t v: with D = diag(M_t)^-1/2, D M_t D = L L^T and the symmetric
 * L^-1 D K_t D L^-T = Y diag(lambda) Y^T, V = D L^-T Y. Then every column is normalised to
 * v^T M_t v = 1 and lambda is its Rayleigh quotient, and the columns are sorted by lambda.
 * Returns 0, or -1 if the scaled Gram is not numerically positive definite. */
static int ritz_solve(const build_work* w, double V[3][3], double* lambda) {
  const int p = w->p;
  double d[3], L[9], A[9], Y[9], eig[3];
  for (int k = 0; k < p; ++k) d[k] = 1.0 / sqrt(w->Mt[k][k]);
  for (int k = 0; k < p; ++k)
    for (int l = 0; l < p; ++l) {
      F3R_AT(L, p, k, l) = d[k] * w->Mt[k][l] * d[l];
      F3R_AT(A, p, k, l) = d[k] * w->Kt[k][l] * d[l];
    }
  if (f3r_cholesky_factor(L, p)) return -1;
  for (int l = 0; l < p; ++l) forward_solve(L, p, &A[l * p]); /* X = L^-1 K */
  double B[9];
  for (int k = 0; k < p; ++k) /* B = X^T = K L^-T, then L^-1 B */
    for (int l = 0; l < p; ++l) F3R_AT(B, p, k, l) = F3R_AT(A, p, l, k);
  for (int l = 0; l < p; ++l) forward_solve(L, p, &B[l * p]);
  for (int k = 0; k < p; ++k)
    for (int l = 0; l < p; ++l)
      F3R_AT(A, p, k, l) = 0.5 * (F3R_AT(B, p, k, l) + F3R_AT(B, p, l, k));
  f3r_symmetric_eigen(A, p, eig, Y);
  for (int m = 0; m < p; ++m) {
    double* y = &Y[m * p];
    backward_solve(L, p, y);
    double mm = 0, kk = 0;
    for (int k = 0; k < p; ++k)
      for (int l = 0; l < p; ++l) {
        mm += d[k] * y[k] * w->Mt[k][l] * d[l] * y[l];
        kk += d[k] * y[k] * w->Kt[k][l] * d[l] * y[l];
      }
    for (int k = 0; k < p; ++k) V[k][m] = d[k] * y[k] / sqrt(mm);
    lambda[m] = kk / mm;
  }
  for (int m = 1; m < p; ++m) /* insertion sort of the columns by lambda */
    for (int i = m; i > 0 && lambda[i] < lambda[i - 1]; --i) {
      const double t = lambda[i];
      lambda[i] = lambda[i - 1];
      lambda[i - 1] = t;
      for (int k = 0; k < p; ++k) {
        const double v = V[k][i];
        V[k][i] = V[k][i - 1];
        V[k][i - 1] = v;
      }
    }
  return 0;
}

/* The corrections' constants, signs and CV from V (see the top of the file). */
static void finish_corrections(f3r_beam_basis* b, const build_work* w, double V[3][3],
                               const double* lambda) {
  const int r = b->modes, p = w->p;
  double tm[3], tf[3], tt[3]; /* mean, first moment and tip of the residuals t_k */
  for (int k = 0; k < p; ++k) {
    const shape_def* s = w->shape[k];
    tm[k] = s->mean;
    tf[k] = s->first_moment;
    tt[k] = s->tip;
    for (int j = 0; j < r; ++j) {
      tm[k] -= w->C[j][k] * b->mean[j];
      tf[k] -= w->C[j][k] * b->first_moment[j];
      tt[k] -= w->C[j][k] * b->tip[j];
    }
  }
  for (int m = 0; m < p; ++m) {
    double mean = 0, first = 0, tip = 0;
    for (int k = 0; k < p; ++k) {
      mean += V[k][m] * tm[k];
      first += V[k][m] * tf[k];
      tip += V[k][m] * tt[k];
    }
    if (b->end == F3R_BEAM_FIXED_PINNED) tip = 0.0; /* the pin: exact */
    const double sign = (b->end == F3R_BEAM_FIXED_FREE ? tip : mean) < 0 ? -1.0 : 1.0;
    const int f = r + m;
    b->mean[f] = sign * mean;
    b->first_moment[f] = sign * first;
    b->tip[f] = sign * tip;
    b->stiffness[f] = lambda[m];
    b->alpha[f] = sqrt(sqrt(lambda[m]));
    for (int k = 0; k < p; ++k) b->V[k][m] = sign * V[k][m];
    for (int j = 0; j < r; ++j) {
      double cv = 0;
      for (int k = 0; k < p; ++k) cv += w->C[j][k] * b->V[k][m];
      b->CV[j][m] = cv;
    }
  }
}

static int popcount3(unsigned set) {
  return (int)(set & 1u) + (int)((set >> 1) & 1u) + (int)((set >> 2) & 1u);
}

int f3r_beam_basis_build(f3r_beam_end end, int modes, unsigned shape_set, f3r_beam_basis* out) {
  if (!out || (end != F3R_BEAM_FIXED_FREE && end != F3R_BEAM_FIXED_PINNED)) return -1;
  if (modes < 1 || modes > F3R_MAX_MODES || (shape_set & ~7u)) return -1;
  if (end == F3R_BEAM_FIXED_PINNED && (shape_set & F3R_SHAPE_TIP_FORCE)) return -1;
  if (modes + popcount3(shape_set) > F3R_MAX_MODES) return -1;
  memset(out, 0, sizeof *out);
  out->end = end;
  out->modes = out->count = modes;
  if (f3r_beam_mode_constants(end, modes, out->alpha, out->mean, out->first_moment, out->tip))
    return -1;
  for (int j = 0; j < modes; ++j) {
    const double a2 = out->alpha[j] * out->alpha[j];
    out->stiffness[j] = a2 * a2; /* as model.c: int psi_j''^2 = alpha_j^4 */
  }
  if (!shape_set) return 0;
  build_work w;
  memset(&w, 0, sizeof w);
  for (unsigned bit = 1; bit <= 4; bit <<= 1)
    if (shape_set & bit) w.shape[w.p++] = find_shape(end, bit);
  for (int j = 0; j < modes; ++j)
    for (int k = 0; k < w.p; ++k) {
      const double* q = w.shape[k]->load;
      w.C[j][k] = (q[0] * out->tip[j] + q[1] * out->mean[j] + q[2] * out->first_moment[j]) /
                  out->stiffness[j];
    }
  residual_grams(out, &w);
  double ratio[3], V[3][3] = {{0}}, lambda[3];
  drop_weak_shapes(&w, ratio);
  if (w.p == 0) return 0;
  if (ritz_solve(&w, V, lambda)) return -1;
  finish_corrections(out, &w, V, lambda);
  for (int k = 0; k < w.p; ++k) {
    out->shape_kind[k] = w.shape[k]->kind;
    out->residual_ratio[k] = ratio[k];
  }
  out->shapes = w.p;
  out->count = modes + w.p;
  return 0;
}

void f3r_beam_basis_eval(const f3r_beam_basis* b, int j, double xi, double* phi, double* dphi,
                         double* ddphi) {
  if (j < b->modes) {
    f3r_beam_mode_eval(b->end, b->alpha[j], xi, phi, dphi, ddphi);
    return;
  }
  const int m = j - b->modes;
  double v = 0, dv = 0, ddv = 0;
  for (int k = 0; k < b->shapes; ++k) {
    double s, ds, dds;
    shape_eval(find_shape(b->end, b->shape_kind[k]), xi, &s, &ds, &dds);
    v += b->V[k][m] * s;
    dv += b->V[k][m] * ds;
    ddv += b->V[k][m] * dds;
  }
  for (int i = 0; i < b->modes; ++i) {
    double s, ds, dds;
    f3r_beam_mode_eval(b->end, b->alpha[i], xi, &s, &ds, &dds);
    v -= b->CV[i][m] * s;
    dv -= b->CV[i][m] * ds;
    ddv -= b->CV[i][m] * dds;
  }
  if (phi) *phi = v;
  if (dphi) *dphi = dv;
  if (ddphi) *ddphi = ddv;
}

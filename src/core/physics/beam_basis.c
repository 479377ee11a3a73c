/* The link basis with static correction shapes (beam_basis.h; issue 28).
 *
 * Numerics (test/reference/static_correction_reference.py and its derivation):
 * - The residual Grams M_t = int t_k t_l and K_t = int t_k'' t_l'' come from composite
 *   Gauss-Legendre quadrature of the pointwise residual t_k(xi) = s_k(xi) - sum_j C_jk psi_j(xi),
 *   never from S - C^T C: that subtraction loses eps (|s|/|t|)^2, garbage in doubles at r = 10
 *   (|t|/|s| ~ 1e-6..1e-8); the pointwise residual loses eps |s|/|t|.
 * - Everything the cancellation touches is formed in long double (x86-64: 64-bit mantissa),
 *   with beam_modes.c's formulas for the same double roots and a long double Gauss-Legendre rule:
 *   the couplings C, the residual and its Grams, the constants, and V and CV themselves.
 * - The couplings are C = G^-1 B, B_jk = int psi_j s_k, G_ij = int psi_i psi_j, by quadrature
 *   (see couplings()). The derivation's closed form alpha_j^4 C_jk = F tip_j + q0 mean_j +
 *   q1 first_moment_j holds for exact roots only; the test checks it to 1e-15.
 * - Measured with 192-bit quadrature of the stored basis (fixed-free r = 3, all three shapes):
 *   max |int phi_i phi_j - delta_ij| 1.2e-10 in doubles throughout, 2e-13 now.
 * - A shape whose residual is below F3R_SHAPE_DROP_RATIO of itself is dropped, and so is the
 *   weakest shape while the unit-diagonal residual Gram has an eigenvalue below 1e-10 (mutual
 *   near-dependence). The rest is a p x p (p <= 3) symmetric-definite eigenproblem: Cholesky of
 *   the unit-diagonal M_t, Jacobi on L^-1 K_t L^-T (dense.h, doubles: well conditioned once
 *   scaled), then each column normalised and its Rayleigh quotient taken in long double.
 * - The constants of a correction, key(phi_m) = sum_k V_km key(t_k) with key(t_k) = key(s_k) -
 *   sum_j C_jk key(psi_j), use the shapes' exact rational integrals and the modes' closed-form
 *   constants (exact integrals of the evaluated modes): the same cancellation as quadrature of
 *   t_k, once instead of per node, and no truncation. The fixed-pinned tip is exactly 0. */
#include "beam_basis.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "dense.h"

/* As beam_modes.c: panels of 12 points, each spanning at most 1 rad of the highest kept mode's
 * oscillation and boundary layer (alpha_r xi), where a degree-23 rule is exact to rounding; 64
 * for mode 20, as beam_modes.c integrates every mode (measured there: converged at 16 panels for
 * mode 20). The shapes are polynomials of degree 5 at most, exact on any panel, so fewer panels
 * for fewer modes change nothing but the time: a basis of 1 mode + shapes takes 8 panels, and
 * the accuracy knob builds several while it chooses. At least 8, at most 64. */
#define F3R_BASIS_MAX_PANELS 64
#define F3R_BASIS_MIN_PANELS 8
#define F3R_BASIS_POINTS 12
/* Second drop guard: the smallest eigenvalue of the unit-diagonal residual Gram. Measured
 * 2e-5 at worst (fixed-free r = 1 with all three shapes), so it only guards degenerate input. */
#define F3R_SHAPE_DEPENDENCE 1e-10

/* A static shape: s(xi) = sum_a c[a] xi^a with c = num / den exactly (long double division) */
typedef struct {
  unsigned kind;
  double num[6], den[6];
  double load[3]; /* tip force F, q0, q1: s'''' = q0 + q1 xi, s'''(1) = -F */
  double mean[2], first_moment[2], tip[2], mass[2]; /* int s, int xi s, s(1), int s^2: num, den */
} shape_def;

static const shape_def kFreeShapes[3] = {
    {F3R_SHAPE_TIP_FORCE,
     {0, 0, 1, -1, 0, 0},
     {1, 1, 2, 6, 1, 1},
     {1, 0, 0},
     {1, 8},
     {11, 120},
     {1, 3},
     {11, 420}},
    {F3R_SHAPE_UNIFORM_LOAD,
     {0, 0, 1, -1, 1, 0},
     {1, 1, 4, 6, 24, 1},
     {0, 1, 0},
     {1, 20},
     {13, 360},
     {1, 8},
     {13, 3240}},
    {F3R_SHAPE_LINEAR_LOAD,
     {0, 0, 1, -1, 0, 1},
     {1, 1, 6, 12, 1, 120},
     {0, 0, 1},
     {13, 360},
     {11, 420},
     {11, 120},
     {2641, 1247400}},
};
static const shape_def kPinnedShapes[2] = {
    {F3R_SHAPE_UNIFORM_LOAD,
     {0, 0, 1, -5, 1, 0},
     {1, 1, 16, 48, 24, 1},
     {0, 1, 0},
     {1, 320},
     {1, 576},
     {0, 1},
     {19, 1451520}},
    {F3R_SHAPE_LINEAR_LOAD,
     {0, 0, 7, -3, 0, 1},
     {1, 1, 240, 80, 1, 120},
     {0, 0, 1},
     {1, 576},
     {11, 11200},
     {0, 1},
     {181, 44352000}},
};

static long double ratio_ld(const double* f) { return (long double)f[0] / f[1]; }

static const shape_def* find_shape(f3r_beam_end end, unsigned kind) {
  const shape_def* list = end == F3R_BEAM_FIXED_FREE ? kFreeShapes : kPinnedShapes;
  const int n = end == F3R_BEAM_FIXED_FREE ? 3 : 2;
  for (int k = 0; k < n; ++k)
    if (list[k].kind == kind) return &list[k];
  return NULL;
}

/* s, s', s'' of a shape at xi (Horner). */
static void shape_eval(const shape_def* s, long double xi, long double* v, long double* dv,
                       long double* ddv) {
  long double p = 0, dp = 0, ddp = 0;
  for (int a = 5; a >= 0; --a) {
    ddp = ddp * xi + dp * 2.0L;
    dp = dp * xi + p;
    p = p * xi + (long double)s->num[a] / s->den[a];
  }
  if (v) *v = p;
  if (dv) *dv = dp;
  if (ddv) *ddv = ddp;
}

/* sin x and cos x in long double. glibc's sincosl reduces x once where sinl and cosl each do,
 * a Payne-Hanek reduction for any |x| > pi/4 in long double, and then runs the same kernels:
 * the same bits (checked on 2e7 arguments in -5..125), at half the reductions of a build. */
static void sin_cos_ld(long double x, long double* s, long double* c) {
#ifdef __GLIBC__
  sincosl(x, s, c);
#else
  *s = sinl(x);
  *c = cosl(x);
#endif
}

/* A mode's terms that do not depend on xi, for mode_at and mode_constants_ld: its end and root,
 * cos, sin and exp(-) of the root, sigma, and the factors of its two boundary layers. */
typedef struct {
  f3r_beam_end end;
  long double a, ca, sa, em, sigma, k1, den, k2;
} mode_terms;

static mode_terms mode_terms_of(f3r_beam_end end, double alpha) {
  const long double a = alpha, s = end == F3R_BEAM_FIXED_FREE ? 1.0L : -1.0L;
  long double ca, sa;
  sin_cos_ld(a, &sa, &ca);
  const long double em = expl(-a), em2 = em * em;
  const long double den = 2.0L * sa * em + s * (1.0L - em2);
  const long double sigma = (2.0L * ca * em + s * (1.0L + em2)) / den;
  return (mode_terms){end, a, ca, sa, em, sigma, sa - ca - s * em, den, 0.5L * (1.0L + sigma)};
}

/* f3r_beam_mode_eval's cancellation-free form (beam_modes.c) in long double, same double root. */
static void mode_at(const mode_terms* m, long double xi, long double* psi, long double* dpsi,
                    long double* ddpsi) {
  const long double a = m->a, sigma = m->sigma;
  const long double e1 = m->k1 * expl(a * (xi - 1.0L)) / m->den;
  const long double e2 = m->k2 * expl(-a * xi);
  long double c, sn;
  sin_cos_ld(a * xi, &sn, &c);
  if (psi) *psi = c - sigma * sn - e1 - e2;
  if (dpsi) *dpsi = a * (-sn - sigma * c - e1 + e2);
  if (ddpsi) *ddpsi = a * a * (-c + sigma * sn - e1 - e2);
}

static void mode_ld(f3r_beam_end end, double alpha, long double xi, long double* psi,
                    long double* dpsi, long double* ddpsi) {
  const mode_terms m = mode_terms_of(end, alpha);
  mode_at(&m, xi, psi, dpsi, ddpsi);
}

/* f3r_beam_mode_constants' term-by-term closed forms in long double: int psi, int xi psi and
 * psi(1) (exactly 0 at a pin). */
static void mode_constants_ld(const mode_terms* t, long double* out) {
  const long double a = t->a, ca = t->ca, sa = t->sa, em = t->em, sigma = t->sigma;
  const long double k1 = t->k1 / t->den, k2 = t->k2;
  const long double decay = (1.0L - em) / a, decay2 = (1.0L - em) / (a * a);
  out[0] = sa / a - sigma * (1.0L - ca) / a - k1 * decay - k2 * decay;
  out[1] = sa / a + (ca - 1.0L) / (a * a) - sigma * (-ca / a + sa / (a * a)) -
           k1 * (1.0L / a - decay2) - k2 * (decay2 - em / a);
  out[2] = 0.0L;
  if (t->end == F3R_BEAM_FIXED_FREE) mode_at(t, 1.0L, &out[2], NULL, NULL);
}

/* The n-point Gauss-Legendre rule on [0, 1] in long double (beam_modes.c's in double): with
 * double weights, int psi_j s_k is only good to 1e-16 relative, and V ~ |s| / |t| multiplies
 * that error. Newton on the three-term recurrence from Tricomi's guess; mirrored. */
static void gauss_legendre_ld(int n, long double* nodes, long double* weights) {
  for (int i = 0; i < (n + 1) / 2; ++i) {
    long double z = cosl(3.14159265358979323846264338327950288L * (i + 0.75L) / (n + 0.5L)), dp = 0;
    for (int it = 0; it < 100; ++it) {
      long double p = 1.0L, prev = 0.0L;
      for (int k = 1; k <= n; ++k) {
        const long double next = ((2.0L * k - 1.0L) * z * p - (k - 1.0L) * prev) / k;
        prev = p;
        p = next;
      }
      dp = n * (z * p - prev) / (z * z - 1.0L);
      const long double step = p / dp;
      z -= step;
      if (fabsl(step) < 1e-19L && it > 2) break;
    }
    const long double w = 1.0L / ((1.0L - z * z) * dp * dp);
    nodes[i] = 0.5L * (1.0L - z);
    nodes[n - 1 - i] = 0.5L * (1.0L + z);
    weights[i] = weights[n - 1 - i] = w;
  }
}

/* The work of building: the shapes asked for, in tip, uniform, linear order. */
typedef struct {
  int p;
  const shape_def* shape[3];
  long double mode[F3R_MAX_MODES][3]; /* mean, first moment, tip of psi_j */
  long double C[F3R_MAX_MODES][3];    /* int psi_j s_k */
  long double Mt[3][3], Kt[3][3];     /* the residuals' Grams */
  int panels;                         /* of the composite rule, by the highest mode */
  long double x[F3R_BASIS_POINTS], wt[F3R_BASIS_POINTS]; /* one panel's Gauss-Legendre rule */
  mode_terms terms[F3R_MAX_MODES]; /* of the kept modes, formed once a build */
  long double* psi; /* the kept modes and their second derivatives at every node (panels x */
  long double* dd;  /* F3R_BASIS_POINTS x modes): two long double sin, cos and exp each */
} build_work;

/* Panels of the composite rule for modes up to root alpha_r: about one per radian of alpha_r. */
static int panels_for(double alpha_r) {
  const int panels = (int)ceil(alpha_r);
  return panels < F3R_BASIS_MIN_PANELS   ? F3R_BASIS_MIN_PANELS
         : panels > F3R_BASIS_MAX_PANELS ? F3R_BASIS_MAX_PANELS
                                         : panels;
}

/* The node of panel `panel` and point q, in [0, 1]. */
static long double node_at(const build_work* w, int panel, int q) {
  return (panel + w->x[q]) / w->panels;
}

/* w->psi and w->dd at every node, once: couplings and residual_grams both read them, and the
 * long double trigonometry (a Payne-Hanek reduction per call in glibc) was most of a build. */
static void evaluate_modes(int r, build_work* w) {
  for (int panel = 0, n = 0; panel < w->panels; ++panel)
    for (int q = 0; q < F3R_BASIS_POINTS; ++q, n += r)
      for (int j = 0; j < r; ++j)
        mode_at(&w->terms[j], node_at(w, panel, q), &w->psi[n + j], NULL, &w->dd[n + j]);
}

/* C = G^-1 B with B_jk = int psi_j s_k and the modes' Gram G_ij = int psi_i psi_j, by the
 * composite rule in long double, so that t_k is mass-orthogonal to the modes as evaluated.
 * The closed form (F tip_j + q0 mean_j + q1 first_moment_j) / alpha_j^4 (checked in the test)
 * assumes exact roots and G = I; for the double roots both hold to ~1e-16, and that error times
 * |CV| ~ |s| / |t| (up to 1e7) left int phi_m psi_j at 2e-12..3e-10 for r = 2..5. G = I + E
 * with |E| ~ 1e-16, so G^-1 = I - E to 1e-32. */
static void couplings(const f3r_beam_basis* b, build_work* w) {
  const long double* wt = w->wt;
  long double B[F3R_MAX_MODES][3] = {{0}}, E[F3R_MAX_MODES][F3R_MAX_MODES] = {{0}};
  const int r = b->modes;
  const mode_terms* terms = w->terms;
  for (int j = 0; j < r; ++j) mode_constants_ld(&terms[j], w->mode[j]);
  for (int panel = 0, n = 0; panel < w->panels; ++panel)
    for (int q = 0; q < F3R_BASIS_POINTS; ++q, n += r) {
      const long double xi = node_at(w, panel, q), wq = wt[q] / w->panels;
      const long double* psi = w->psi + n;
      long double s[3];
      for (int k = 0; k < w->p; ++k) shape_eval(w->shape[k], xi, &s[k], NULL, NULL);
      for (int j = 0; j < r; ++j) {
        for (int k = 0; k < w->p; ++k) B[j][k] += wq * psi[j] * s[k];
        for (int i = 0; i < r; ++i) E[j][i] += wq * psi[j] * psi[i];
      }
    }
  for (int j = 0; j < r; ++j) E[j][j] -= 1.0L;
  for (int j = 0; j < r; ++j)
    for (int k = 0; k < w->p; ++k) {
      w->C[j][k] = B[j][k];
      for (int i = 0; i < r; ++i) w->C[j][k] -= E[j][i] * B[i][k];
    }
}

/* M_t and K_t by composite Gauss-Legendre quadrature of the pointwise residual. */
static void residual_grams(const f3r_beam_basis* b, build_work* w) {
  const long double* wt = w->wt;
  memset(w->Mt, 0, sizeof w->Mt);
  memset(w->Kt, 0, sizeof w->Kt);
  for (int panel = 0, n = 0; panel < w->panels; ++panel) {
    long double pm[3][3] = {{0}}, pk[3][3] = {{0}}; /* per panel, then added */
    for (int q = 0; q < F3R_BASIS_POINTS; ++q, n += b->modes) {
      const long double xi = node_at(w, panel, q);
      const long double wq = wt[q] / w->panels;
      const long double *psi = w->psi + n, *dd = w->dd + n;
      long double t[3], tdd[3];
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

/* Removes shape k from the work (its couplings and its Gram rows and columns). */
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
      F3R_AT(A, w->p, k, l) = (double)(w->Mt[k][l] / sqrtl(w->Mt[k][k] * w->Mt[l][l]));
  f3r_symmetric_eigen(A, w->p, eig, NULL);
  double lo = eig[0];
  for (int k = 1; k < w->p; ++k) lo = fmin(lo, eig[k]);
  return lo;
}

/* The drop tests: residual below F3R_SHAPE_DROP_RATIO of its shape, then the weakest shape
 * while the rest are nearly dependent. ratio[k] receives ||t_k|| / ||s_k||. */
static void drop_weak_shapes(build_work* w, double* ratio) {
  for (int k = 0; k < w->p; ++k)
    ratio[k] = (double)sqrtl(fmaxl(w->Mt[k][k], 0.0L) / ratio_ld(w->shape[k]->mass));
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

/* Sorts the columns of V and lambda by lambda, ascending (insertion sort, p <= 3). */
static void sort_columns(int p, long double V[3][3], long double* lambda) {
  for (int m = 1; m < p; ++m)
    for (int i = m; i > 0 && lambda[i] < lambda[i - 1]; --i) {
      const long double t = lambda[i];
      lambda[i] = lambda[i - 1];
      lambda[i - 1] = t;
      for (int k = 0; k < p; ++k) {
        const long double v = V[k][i];
        V[k][i] = V[k][i - 1];
        V[k][i - 1] = v;
      }
    }
}

/* K_t v = lambda M_t v: with D = diag(M_t)^-1/2, D M_t D = L L^T and the symmetric
 * L^-1 D K_t D L^-T = Y diag(lambda) Y^T, V = D L^-T Y. Then every column is normalised to
 * v^T M_t v = 1 in long double, lambda is its Rayleigh quotient, and the columns are sorted.
 * Returns 0, or -1 if the scaled Gram is not numerically positive definite. */
static int ritz_solve(const build_work* w, long double V[3][3], long double* lambda) {
  const int p = w->p;
  long double d[3];
  double L[9], A[9], B[9], Y[9], eig[3];
  for (int k = 0; k < p; ++k) d[k] = 1.0L / sqrtl(w->Mt[k][k]);
  for (int k = 0; k < p; ++k)
    for (int l = 0; l < p; ++l) {
      F3R_AT(L, p, k, l) = (double)(d[k] * w->Mt[k][l] * d[l]);
      F3R_AT(A, p, k, l) = (double)(d[k] * w->Kt[k][l] * d[l]);
    }
  if (f3r_cholesky_factor(L, p)) return -1;
  for (int l = 0; l < p; ++l) forward_solve(L, p, &A[l * p]); /* X = L^-1 K */
  for (int k = 0; k < p; ++k)                                 /* B = X^T = K L^-T, then L^-1 B */
    for (int l = 0; l < p; ++l) F3R_AT(B, p, k, l) = F3R_AT(A, p, l, k);
  for (int l = 0; l < p; ++l) forward_solve(L, p, &B[l * p]);
  for (int k = 0; k < p; ++k)
    for (int l = 0; l < p; ++l)
      F3R_AT(A, p, k, l) = 0.5 * (F3R_AT(B, p, k, l) + F3R_AT(B, p, l, k));
  f3r_symmetric_eigen(A, p, eig, Y);
  for (int m = 0; m < p; ++m) {
    double* y = &Y[m * p];
    backward_solve(L, p, y);
    long double v[3], mm = 0, kk = 0;
    for (int k = 0; k < p; ++k) v[k] = d[k] * y[k];
    for (int k = 0; k < p; ++k)
      for (int l = 0; l < p; ++l) {
        mm += v[k] * w->Mt[k][l] * v[l];
        kk += v[k] * w->Kt[k][l] * v[l];
      }
    for (int k = 0; k < p; ++k) V[k][m] = v[k] / sqrtl(mm);
    lambda[m] = kk / mm;
  }
  sort_columns(p, V, lambda);
  return 0;
}

/* The corrections' constants, signs and CV from V (see the top of the file). */
static void finish_corrections(f3r_beam_basis* b, const build_work* w, long double V[3][3],
                               const long double* lambda, int functions) {
  const int r = b->modes, p = w->p;
  long double tc[3][3]; /* mean, first moment and tip of the residuals t_k */
  for (int k = 0; k < p; ++k) {
    const shape_def* s = w->shape[k];
    tc[k][0] = ratio_ld(s->mean);
    tc[k][1] = ratio_ld(s->first_moment);
    tc[k][2] = ratio_ld(s->tip);
    for (int j = 0; j < r; ++j)
      for (int c = 0; c < 3; ++c) tc[k][c] -= w->C[j][k] * w->mode[j][c];
  }
  for (int m = 0; m < functions; ++m) {
    long double key[3] = {0, 0, 0};
    for (int k = 0; k < p; ++k)
      for (int c = 0; c < 3; ++c) key[c] += V[k][m] * tc[k][c];
    if (b->end == F3R_BEAM_FIXED_PINNED) key[2] = 0.0L; /* the pin: exact */
    const long double sign = (b->end == F3R_BEAM_FIXED_FREE ? key[2] : key[0]) < 0 ? -1 : 1;
    const int f = r + m;
    b->mean[f] = (double)(sign * key[0]);
    b->first_moment[f] = (double)(sign * key[1]);
    b->tip[f] = (double)(sign * key[2]);
    b->stiffness[f] = (double)lambda[m];
    b->alpha[f] = (double)sqrtl(sqrtl(lambda[m]));
    for (int k = 0; k < p; ++k) b->V[k][m] = sign * V[k][m];
    for (int j = 0; j < r; ++j) {
      long double cv = 0;
      for (int k = 0; k < p; ++k) cv += w->C[j][k] * sign * V[k][m];
      b->CV[j][m] = cv;
    }
  }
}

static int popcount3(unsigned set) {
  return (int)(set & 1u) + (int)((set >> 1) & 1u) + (int)((set >> 2) & 1u);
}

/* The mixed correction's V column and stiffness: the residuals' combination (1, mix) over (tip,
 * uniform), normalised to v^T M_t v = 1, its stiffness the Rayleigh quotient. Returns -1 if its
 * mass is not positive. */
static int mixed_direction(const build_work* w, double mix, long double V[3][3],
                           long double* lambda) {
  const long double d[2] = {1.0L, (long double)mix};
  long double mm = 0, kk = 0;
  for (int k = 0; k < 2; ++k)
    for (int l = 0; l < 2; ++l) {
      mm += d[k] * w->Mt[k][l] * d[l];
      kk += d[k] * w->Kt[k][l] * d[l];
    }
  if (!(mm > 0)) return -1;
  for (int k = 0; k < 2; ++k) V[k][0] = d[k] / sqrtl(mm);
  lambda[0] = kk / mm;
  return 0;
}

/* f3r_beam_basis_build, and with mix (not NULL) build_mixed's single correction. */
static int build(f3r_beam_end end, int modes, unsigned shape_set, const double* mix,
                 f3r_beam_basis* out) {
  if (!out || (end != F3R_BEAM_FIXED_FREE && end != F3R_BEAM_FIXED_PINNED)) return -1;
  if (modes < 1 || modes > F3R_MAX_MODES || (shape_set & ~7u)) return -1;
  if (end == F3R_BEAM_FIXED_PINNED && (shape_set & F3R_SHAPE_TIP_FORCE)) return -1;
  if (modes + (mix ? 1 : popcount3(shape_set)) > F3R_MAX_MODES) return -1;
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
  w.panels = panels_for(out->alpha[modes - 1]);
  gauss_legendre_ld(F3R_BASIS_POINTS, w.x, w.wt);
  for (int j = 0; j < modes; ++j) w.terms[j] = mode_terms_of(end, out->alpha[j]);
  for (unsigned bit = 1; bit <= 4; bit <<= 1)
    if (shape_set & bit) w.shape[w.p++] = find_shape(end, bit);
  const size_t values = (size_t)w.panels * F3R_BASIS_POINTS * (size_t)modes;
  w.psi = malloc(2 * values * sizeof(long double));
  if (!w.psi) return F3R_BASIS_NO_MEMORY;
  w.dd = w.psi + values;
  evaluate_modes(modes, &w);
  couplings(out, &w);
  residual_grams(out, &w);
  free(w.psi);
  double ratio[3];
  long double V[3][3] = {{0}}, lambda[3];
  drop_weak_shapes(&w, ratio);
  if (w.p == 0) return 0;
  const int mixed = mix && w.p == 2, functions = mixed ? 1 : w.p;
  if (mixed ? mixed_direction(&w, *mix, V, lambda) : ritz_solve(&w, V, lambda)) return -1;
  finish_corrections(out, &w, V, lambda, functions);
  for (int k = 0; k < w.p; ++k) {
    out->shape_kind[k] = w.shape[k]->kind;
    out->residual_ratio[k] = ratio[k];
  }
  out->shapes = w.p;
  out->corrections = functions;
  out->count = modes + functions;
  out->mixed = mixed;
  out->mix = mixed ? *mix : 0.0;
  return 0;
}

int f3r_beam_basis_build(f3r_beam_end end, int modes, unsigned shape_set, f3r_beam_basis* out) {
  return build(end, modes, shape_set, NULL, out);
}

int f3r_beam_basis_build_mixed(int modes, double mix, f3r_beam_basis* out) {
  if (!isfinite(mix)) return -1;
  return build(F3R_BEAM_FIXED_FREE, modes, F3R_SHAPE_TIP_FORCE | F3R_SHAPE_UNIFORM_LOAD, &mix, out);
}

/* Evaluated in long double, so the cancellation in V s - CV psi costs 2048x less. */
void f3r_beam_basis_eval(const f3r_beam_basis* b, int j, double xi, double* phi, double* dphi,
                         double* ddphi) {
  if (j < b->modes) {
    f3r_beam_mode_eval(b->end, b->alpha[j], xi, phi, dphi, ddphi);
    return;
  }
  const int m = j - b->modes;
  long double v = 0, dv = 0, ddv = 0, s, ds, dds;
  for (int k = 0; k < b->shapes; ++k) {
    shape_eval(find_shape(b->end, b->shape_kind[k]), xi, &s, &ds, &dds);
    v += b->V[k][m] * s;
    dv += b->V[k][m] * ds;
    ddv += b->V[k][m] * dds;
  }
  for (int i = 0; i < b->modes; ++i) {
    mode_ld(b->end, b->alpha[i], xi, &s, &ds, &dds);
    v -= b->CV[i][m] * s;
    dv -= b->CV[i][m] * ds;
    ddv -= b->CV[i][m] * dds;
  }
  if (phi) *phi = (double)v;
  if (dphi) *dphi = (double)dv;
  if (ddphi) *ddphi = (double)ddv;
}

/* Assumed modes of the clamped beam: frequency-equation roots, cancellation-free evaluation and
 * modal integrals in closed form (what the model needs) and by composite Gauss-Legendre
 * quadrature (Gram and bending matrices; the closed forms' check). See include/flex3rpr/beam_modes.h.
 *
 * With s = +1 (fixed-free) or -1 (fixed-pinned) and a = alpha, multiplying numerator and
 * denominator of sigma by 2 e^-a gives
 *   sigma = (cos a + s cosh a)/(sin a + s sinh a)
 *         = (2 cos a e^-a + s (1 + e^-2a)) / (2 sin a e^-a + s (1 - e^-2a)),
 *   cosh(a xi) - sigma sinh(a xi) = E1 + E2,   E2 = (1 + sigma)/2 e^(-a xi),
 *   E1 = (1 - sigma)/2 e^(a xi) = (sin a - cos a - s e^-a) e^(a (xi - 1)) / (2 sin a e^-a + s (1 - e^-2a)).
 * 1 - sigma ~ e^-a is formed without subtracting, and every exponential decays, so nothing
 * cancels for large a. E1' = a E1 and E2' = -a E2 give the derivatives. */
#include <math.h>
#include <string.h>

#include "flex3rpr/beam_modes.h"

/* M_PI is not part of strict C11. */
#define F3R_PI 3.14159265358979323846264338327950288

/* Mode 20 has ~10 periods and a boundary layer of width 1/alpha ~ 1/63 at xi = 1; 64 panels of
 * 12 points put ~1 rad of either in each panel, where a degree-23 rule is exact to rounding.
 * Measured for 20 modes, both ends: Gram matrix within 2e-15 of the identity (rounding; already
 * converged at 16 panels, 2e-11 at 8), so 64 leaves a 4x margin. */
#define F3R_QUAD_PANELS 64
#define F3R_QUAD_POINTS 12

/* The frequency equations in forms with bounded terms: tan a = tanh a as sin a - cos a tanh a = 0,
 * and cos a cosh a + 1 = 0 divided by cosh a. */
static double frequency_function(f3r_beam_end end, double a, double* slope) {
  const double c = cos(a), s = sin(a), t = tanh(a);
  if (end == F3R_BEAM_FIXED_PINNED) {
    *slope = c + s * t - c * (1.0 - t * t);
    return s - c * t;
  }
  const double sech = 1.0 / cosh(a);
  *slope = -s - t * sech;
  return c + sech;
}

int f3r_beam_roots(f3r_beam_end end, int count, double* alpha) {
  if (count < 1 || count > F3R_MAX_MODES) return -1;
  for (int j = 1; j <= count; ++j) {
    double a;
    if (end == F3R_BEAM_FIXED_PINNED)
      a = (j + 0.25) * F3R_PI;
    else /* the first fixed-free root is far from its asymptote (j - 0.5) pi */
      a = j == 1 ? 1.875 : (j - 0.5) * F3R_PI;
    for (int it = 0; it < 50; ++it) {
      double slope;
      const double step = frequency_function(end, a, &slope) / slope;
      a -= step;
      if (fabs(step) < 1e-15 * a) break;
    }
    alpha[j - 1] = a;
  }
  return 0;
}

void f3r_beam_mode_eval(f3r_beam_end end, double a, double xi, double* psi, double* dpsi,
                        double* ddpsi) {
  const double s = end == F3R_BEAM_FIXED_FREE ? 1.0 : -1.0;
  const double ca = cos(a), sa = sin(a), em = exp(-a), em2 = em * em;
  const double den = 2.0 * sa * em + s * (1.0 - em2);
  const double sigma = (2.0 * ca * em + s * (1.0 + em2)) / den;
  const double e1 = (sa - ca - s * em) * exp(a * (xi - 1.0)) / den;
  const double e2 = 0.5 * (1.0 + sigma) * exp(-a * xi);
  const double c = cos(a * xi), sn = sin(a * xi);
  if (psi) *psi = c - sigma * sn - e1 - e2;
  if (dpsi) *dpsi = a * (-sn - sigma * c - e1 + e2);
  if (ddpsi) *ddpsi = a * a * (-c + sigma * sn - e1 - e2);
}

/* psi = cos a xi - sigma sin a xi - K1 e^(a (xi - 1)) - K2 e^(-a xi) (the form above), integrated
 * term by term; every term is O(1/a) and every exponential decays, so nothing cancels:
 *   int cos = sin a / a                     int xi cos = sin a / a + (cos a - 1) / a^2
 *   int sin = (1 - cos a) / a               int xi sin = -cos a / a + sin a / a^2
 *   int e^(a (xi - 1)) = (1 - e^-a) / a     int xi e^(a (xi - 1)) = 1/a - (1 - e^-a) / a^2
 *   int e^(-a xi) = (1 - e^-a) / a          int xi e^(-a xi) = (1 - e^-a) / a^2 - e^-a / a */
int f3r_beam_mode_constants(f3r_beam_end end, int count, double* alpha, double* mean,
                            double* first_moment, double* tip) {
  if (f3r_beam_roots(end, count, alpha)) return -1;
  const double s = end == F3R_BEAM_FIXED_FREE ? 1.0 : -1.0;
  for (int j = 0; j < count; ++j) {
    const double a = alpha[j], ca = cos(a), sa = sin(a), em = exp(-a), em2 = em * em;
    const double den = 2.0 * sa * em + s * (1.0 - em2);
    const double sigma = (2.0 * ca * em + s * (1.0 + em2)) / den;
    const double k1 = (sa - ca - s * em) / den, k2 = 0.5 * (1.0 + sigma);
    const double decay = (1.0 - em) / a, decay2 = (1.0 - em) / (a * a);
    if (mean) mean[j] = sa / a - sigma * (1.0 - ca) / a - k1 * decay - k2 * decay;
    if (first_moment)
      first_moment[j] = sa / a + (ca - 1.0) / (a * a) - sigma * (-ca / a + sa / (a * a)) -
                        k1 * (1.0 / a - decay2) - k2 * (decay2 - em / a);
    if (tip) {
      if (end == F3R_BEAM_FIXED_PINNED) /* the pin: exact, not a rounded ~1e-16 */
        tip[j] = 0.0;
      else
        f3r_beam_mode_eval(end, a, 1.0, &tip[j], NULL, NULL);
    }
  }
  return 0;
}

/* Legendre P_n(z) and P_n'(z) by the three-term recurrence (|z| < 1). */
static double legendre(int n, double z, double* dp) {
  double p = 1.0, prev = 0.0;
  for (int k = 1; k <= n; ++k) {
    const double next = ((2.0 * k - 1.0) * z * p - (k - 1.0) * prev) / k;
    prev = p;
    p = next;
  }
  *dp = n * (z * p - prev) / (z * z - 1.0);
  return p;
}

int f3r_gauss_legendre(int n, double* nodes, double* weights) {
  if (n < 1 || n > 64) return -1;
  /* Roots in (0, 1) only, mirrored, so the rule is exactly symmetric. */
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double z = cos(F3R_PI * (i + 0.75) / (n + 0.5)), dp;
    for (int it = 0; it < 100; ++it) {
      const double step = legendre(n, z, &dp) / dp;
      z -= step;
      if (fabs(step) < 1e-15) break;
    }
    if (2 * i + 1 == n) z = 0.0; /* the middle root of odd n is exactly 0 */
    legendre(n, z, &dp);         /* weight from the derivative at the converged root */
    const double w = 1.0 / ((1.0 - z * z) * dp * dp); /* 2/((1-z^2)P'^2), halved for [0, 1] */
    nodes[i] = 0.5 * (1.0 - z);
    nodes[n - 1 - i] = 0.5 * (1.0 + z);
    weights[i] = weights[n - 1 - i] = w;
  }
  return 0;
}

int f3r_beam_modal_integrals(f3r_beam_end end, int count, double* mean, double* first_moment,
                             double* gram, double* bending, double* tip) {
  double alpha[F3R_MAX_MODES];
  if (f3r_beam_roots(end, count, alpha)) return -1;
  double x[F3R_QUAD_POINTS], w[F3R_QUAD_POINTS];
  f3r_gauss_legendre(F3R_QUAD_POINTS, x, w);
  const size_t vec = (size_t)count * sizeof(double), mat = vec * (size_t)count;
  if (mean) memset(mean, 0, vec);
  if (first_moment) memset(first_moment, 0, vec);
  if (gram) memset(gram, 0, mat);
  if (bending) memset(bending, 0, mat);
  if (tip)
    for (int i = 0; i < count; ++i) {
      if (end == F3R_BEAM_FIXED_PINNED) /* the pin: exact, not a rounded ~1e-16 */
        tip[i] = 0.0;
      else
        f3r_beam_mode_eval(end, alpha[i], 1.0, &tip[i], NULL, NULL);
    }
  if (!mean && !first_moment && !gram && !bending) return 0;
  for (int p = 0; p < F3R_QUAD_PANELS; ++p)
    for (int k = 0; k < F3R_QUAD_POINTS; ++k) {
      const double xi = (p + x[k]) / F3R_QUAD_PANELS, wk = w[k] / F3R_QUAD_PANELS;
      double psi[F3R_MAX_MODES], curv[F3R_MAX_MODES];
      for (int i = 0; i < count; ++i)
        f3r_beam_mode_eval(end, alpha[i], xi, &psi[i], NULL, bending ? &curv[i] : NULL);
      for (int i = 0; i < count; ++i) {
        if (mean) mean[i] += wk * psi[i];
        if (first_moment) first_moment[i] += wk * xi * psi[i];
        for (int j = i; j < count; ++j) { /* upper triangle; mirrored below for exact symmetry */
          if (gram) gram[i * count + j] += wk * psi[i] * psi[j];
          if (bending) bending[i * count + j] += wk * curv[i] * curv[j];
        }
      }
    }
  for (int i = 0; i < count; ++i)
    for (int j = 0; j < i; ++j) {
      if (gram) gram[i * count + j] = gram[j * count + i];
      if (bending) bending[i * count + j] = bending[j * count + i];
    }
  return 0;
}

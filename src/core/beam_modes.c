/* Assumed modes of the clamped beam: frequency-equation roots, cancellation-free evaluation and
 * modal integrals by composite Gauss-Legendre quadrature. See include/flex3rpr/beam_modes.h.
 *
 * With s = +1 (fixed-free) or -1 (fixed-pinned) and a = alpha:
 *   sigma = (cos a + s cosh a)/(sin a + s sinh a)
 *         = (2 cos a e^-a + s (1 + e^-2a)) / (2 sin a e^-a + s (1 - e^-2a))
 *   cosh(a xi) - sigma sinh(a xi) = E1 + (1 + sigma)/2 e^(-a xi),
 *   E1 = (1 - sigma)/2 e^(a xi) = (sin a - cos a - s e^-a) e^(a (xi - 1)) / (2 sin a e^-a + s (1 - e^-2a)),
 * using sinh a - cosh a = -e^-a. Every exponential decays, so nothing cancels for large a. */
#include <math.h>
#include <stddef.h>

#include "flex3rpr/beam_modes.h"

/* Quadrature: 64 panels of 12 Gauss points resolve ~10 oscillations and the boundary layer of
 * width 1/alpha at mode 20 to ~1e-15. */
#define F3R_QUAD_PANELS 64
#define F3R_QUAD_POINTS 12

static double frequency_function(f3r_beam_end end, double a, double* slope) {
  if (end == F3R_BEAM_FIXED_PINNED) { /* tan a = tanh a, as sin a - cos a tanh a = 0 */
    const double t = tanh(a);
    *slope = cos(a) + sin(a) * t - cos(a) * (1.0 - t * t);
    return sin(a) - cos(a) * t;
  }
  /* cos a cosh a + 1 = 0, divided by cosh a */
  *slope = -sin(a) - tanh(a) / cosh(a);
  return cos(a) + 1.0 / cosh(a);
}

int f3r_beam_roots(f3r_beam_end end, int count, double* alpha) {
  if (count < 1 || count > F3R_MAX_MODES) return -1;
  for (int j = 1; j <= count; ++j) {
    double a = end == F3R_BEAM_FIXED_PINNED ? (j + 0.25) * M_PI : (j == 1 ? 1.875 : (j - 0.5) * M_PI);
    for (int it = 0; it < 60; ++it) {
      double slope;
      const double f = frequency_function(end, a, &slope);
      const double step = f / slope;
      a -= step;
      if (fabs(step) <= 1e-16 * a) break;
    }
    alpha[j - 1] = a;
  }
  return 0;
}

void f3r_beam_mode_eval(f3r_beam_end end, double a, double xi, double* psi, double* dpsi,
                        double* ddpsi) {
  const double s = end == F3R_BEAM_FIXED_FREE ? 1.0 : -1.0;
  const double em = exp(-a), em2 = em * em;
  const double den = 2.0 * sin(a) * em + s * (1.0 - em2);
  const double sigma = (2.0 * cos(a) * em + s * (1.0 + em2)) / den;
  const double e1 = (sin(a) - cos(a) - s * em) * exp(a * (xi - 1.0)) / den;
  const double e2 = 0.5 * (1.0 + sigma) * exp(-a * xi);
  const double c = cos(a * xi), sn = sin(a * xi);
  if (psi) *psi = c - sigma * sn - e1 - e2;
  if (dpsi) *dpsi = a * (-sn - sigma * c - e1 + e2);
  if (ddpsi) *ddpsi = a * a * (-c + sigma * sn - e1 - e2);
}

int f3r_gauss_legendre(int n, double* nodes, double* weights) {
  if (n < 1 || n > 64) return -1;
  for (int i = 0; i < n; ++i) {
    double z = cos(M_PI * (i + 0.75) / (n + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p1 = 1.0, p0 = 0.0; /* P_k(z) by the three-term recurrence */
      for (int k = 1; k <= n; ++k) {
        const double pm = p0;
        p0 = p1;
        p1 = ((2.0 * k - 1.0) * z * p0 - (k - 1.0) * pm) / k;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double step = p1 / dp;
      z -= step;
      if (fabs(step) < 1e-16) break;
    }
    nodes[i] = 0.5 * (1.0 - z);
    weights[i] = 1.0 / ((1.0 - z * z) * dp * dp);
  }
  return 0;
}

int f3r_beam_modal_integrals(f3r_beam_end end, int count, double* mean, double* first_moment,
                             double* gram, double* bending, double* tip) {
  double alpha[F3R_MAX_MODES];
  if (f3r_beam_roots(end, count, alpha)) return -1;
  double x[F3R_QUAD_POINTS], w[F3R_QUAD_POINTS];
  f3r_gauss_legendre(F3R_QUAD_POINTS, x, w);
  for (int i = 0; i < count; ++i) {
    if (mean) mean[i] = 0.0;
    if (first_moment) first_moment[i] = 0.0;
    if (tip) {
      double at_tip;
      f3r_beam_mode_eval(end, alpha[i], 1.0, &at_tip, NULL, NULL);
      tip[i] = end == F3R_BEAM_FIXED_PINNED ? 0.0 : at_tip;
    }
    for (int j = 0; j < count; ++j) {
      if (gram) gram[i * count + j] = 0.0;
      if (bending) bending[i * count + j] = 0.0;
    }
  }
  for (int p = 0; p < F3R_QUAD_PANELS; ++p)
    for (int k = 0; k < F3R_QUAD_POINTS; ++k) {
      const double xi = (p + x[k]) / F3R_QUAD_PANELS, wk = w[k] / F3R_QUAD_PANELS;
      double psi[F3R_MAX_MODES], curv[F3R_MAX_MODES];
      for (int i = 0; i < count; ++i) f3r_beam_mode_eval(end, alpha[i], xi, &psi[i], NULL, &curv[i]);
      for (int i = 0; i < count; ++i) {
        if (mean) mean[i] += wk * psi[i];
        if (first_moment) first_moment[i] += wk * xi * psi[i];
        for (int j = 0; j < count; ++j) {
          if (gram) gram[i * count + j] += wk * psi[i] * psi[j];
          if (bending) bending[i * count + j] += wk * curv[i] * curv[j];
        }
      }
    }
  return 0;
}

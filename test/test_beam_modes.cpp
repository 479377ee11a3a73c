// Beam modes against independent computations: roots by bisection in long double, the printed
// (cancelling) mode formula evaluated in 256-bit floating point (MPFR), and quadrature identities.
#include <gtest/gtest.h>
#include <mpfr.h>

#include <cmath>

#include "flex3rpr/beam_modes.h"

namespace {

const f3r_beam_end kEnds[] = {F3R_BEAM_FIXED_PINNED, F3R_BEAM_FIXED_FREE};

// Frequency equations as printed, scaled by e^-a so they stay finite.
long double Printed(f3r_beam_end end, long double a) {
  const long double em = expl(-a);
  if (end == F3R_BEAM_FIXED_PINNED)  // tan a - tanh a, times cos a cosh a
    return sinl(a) * 0.5L * (1 + em * em) - cosl(a) * 0.5L * (1 - em * em);
  return cosl(a) * 0.5L * (1 + em * em) + em;  // (cos a cosh a + 1) e^-a
}

long double Bisect(f3r_beam_end end, long double lo, long double hi) {
  long double flo = Printed(end, lo);
  for (int it = 0; it < 200; ++it) {
    const long double mid = 0.5L * (lo + hi), fm = Printed(end, mid);
    if ((fm < 0) == (flo < 0)) { lo = mid; flo = fm; } else { hi = mid; }
  }
  return 0.5L * (lo + hi);
}

TEST(BeamModes, RootsMatchBisectionOfThePrintedEquations) {
  for (auto end : kEnds) {
    double alpha[F3R_MAX_MODES];
    ASSERT_EQ(f3r_beam_roots(end, F3R_MAX_MODES, alpha), 0);
    for (int j = 1; j <= F3R_MAX_MODES; ++j) {
      const long double guess = end == F3R_BEAM_FIXED_PINNED ? (j + 0.25L) * M_PIl : (j - 0.5L) * M_PIl;
      const long double root = Bisect(end, guess - 0.4L, guess + 0.4L);
      EXPECT_NEAR(alpha[j - 1], (double)root, 1e-13 * (double)root) << "end " << end << " mode " << j;
    }
  }
  double a[4];
  f3r_beam_roots(F3R_BEAM_FIXED_FREE, 4, a);
  const double paper[4] = {1.875104069, 4.694091133, 7.854757438, 10.99554073};  // eq. (7)
  for (int j = 0; j < 4; ++j) EXPECT_NEAR(a[j], paper[j], 1e-8);
  f3r_beam_roots(F3R_BEAM_FIXED_PINNED, 3, a);
  EXPECT_NEAR(a[0], 3.926602, 1e-6);  // MODEL.md
  EXPECT_NEAR(a[1], 7.068583, 1e-6);
  EXPECT_NEAR(a[2], 10.210176, 1e-6);
}

// psi, psi', psi'' exactly as printed in eqs. (3) and (5), evaluated with 256-bit MPFR numbers:
// the cancellation of cosh - sigma sinh costs about a/ln(10) < 28 digits, which 77 absorb.
class Mpfr {
 public:
  Mpfr() { mpfr_init2(v_, 256); }
  ~Mpfr() { mpfr_clear(v_); }
  mpfr_ptr get() { return v_; }
 private:
  mpfr_t v_;
};

void PrintedMode(f3r_beam_end end, double alpha, double xi, double out[3]) {
  Mpfr a, ax, c, s, ch, sh, ca, sa, cha, sha, sigma, num, den, t, res;
  mpfr_set_d(a.get(), alpha, MPFR_RNDN);
  mpfr_mul_d(ax.get(), a.get(), xi, MPFR_RNDN);
  mpfr_cos(c.get(), ax.get(), MPFR_RNDN);
  mpfr_sin(s.get(), ax.get(), MPFR_RNDN);
  mpfr_cosh(ch.get(), ax.get(), MPFR_RNDN);
  mpfr_sinh(sh.get(), ax.get(), MPFR_RNDN);
  mpfr_cos(ca.get(), a.get(), MPFR_RNDN);
  mpfr_sin(sa.get(), a.get(), MPFR_RNDN);
  mpfr_cosh(cha.get(), a.get(), MPFR_RNDN);
  mpfr_sinh(sha.get(), a.get(), MPFR_RNDN);
  if (end == F3R_BEAM_FIXED_FREE) {
    mpfr_add(num.get(), ca.get(), cha.get(), MPFR_RNDN);
    mpfr_add(den.get(), sa.get(), sha.get(), MPFR_RNDN);
  } else {
    mpfr_sub(num.get(), ca.get(), cha.get(), MPFR_RNDN);
    mpfr_sub(den.get(), sa.get(), sha.get(), MPFR_RNDN);
  }
  mpfr_div(sigma.get(), num.get(), den.get(), MPFR_RNDN);
  // derivative d of (cos - cosh) - sigma (sin - sinh), divided by a^d:
  //   d = 0: (c - ch) - sigma (s - sh);  d = 1: (-s - sh) - sigma (c - ch);
  //   d = 2: (-c - ch) - sigma (-s - sh)
  for (int d = 0; d < 3; ++d) {
    Mpfr first, second;
    if (d == 0) {
      mpfr_sub(first.get(), c.get(), ch.get(), MPFR_RNDN);
      mpfr_sub(second.get(), s.get(), sh.get(), MPFR_RNDN);
    } else if (d == 1) {
      mpfr_add(first.get(), s.get(), sh.get(), MPFR_RNDN);
      mpfr_neg(first.get(), first.get(), MPFR_RNDN);
      mpfr_sub(second.get(), c.get(), ch.get(), MPFR_RNDN);
    } else {
      mpfr_add(first.get(), c.get(), ch.get(), MPFR_RNDN);
      mpfr_neg(first.get(), first.get(), MPFR_RNDN);
      mpfr_add(second.get(), s.get(), sh.get(), MPFR_RNDN);
      mpfr_neg(second.get(), second.get(), MPFR_RNDN);
    }
    mpfr_mul(t.get(), sigma.get(), second.get(), MPFR_RNDN);
    mpfr_sub(res.get(), first.get(), t.get(), MPFR_RNDN);
    out[d] = mpfr_get_d(res.get(), MPFR_RNDN) * std::pow(alpha, d);
  }
}

TEST(BeamModes, EvaluationHasNoCancellationUpToMode20) {
  for (auto end : kEnds) {
    double alpha[F3R_MAX_MODES];
    f3r_beam_roots(end, F3R_MAX_MODES, alpha);
    for (int j = 0; j < F3R_MAX_MODES; ++j)
      for (int k = 0; k <= 40; ++k) {
        const double xi = k / 40.0;
        double ours[3], ref[3];
        f3r_beam_mode_eval(end, alpha[j], xi, &ours[0], &ours[1], &ours[2]);
        PrintedMode(end, alpha[j], xi, ref);
        for (int d = 0; d < 3; ++d)
          EXPECT_NEAR(ours[d], ref[d], 1e-12 * std::pow(alpha[j], d))
              << "end " << end << " mode " << j + 1 << " xi " << xi << " derivative " << d;
      }
  }
}

TEST(BeamModes, OrthonormalAtTwentyModes) {
  for (auto end : kEnds) {
    const int r = F3R_MAX_MODES;
    double gram[r * r], bending[r * r], alpha[r];
    f3r_beam_roots(end, r, alpha);
    ASSERT_EQ(f3r_beam_modal_integrals(end, r, nullptr, nullptr, gram, bending, nullptr), 0);
    double worst = 0, worst_k = 0;
    for (int i = 0; i < r; ++i)
      for (int j = 0; j < r; ++j) {
        worst = std::max(worst, std::fabs(gram[i * r + j] - (i == j)));
        const double scale = alpha[i] * alpha[i] * alpha[j] * alpha[j];
        const double expected = i == j ? std::pow(alpha[i], 4) : 0.0;
        worst_k = std::max(worst_k, std::fabs(bending[i * r + j] - expected) / scale);
      }
    EXPECT_LT(worst, 1e-12) << "end " << end;
    EXPECT_LT(worst_k, 1e-12) << "end " << end;
  }
}

TEST(BeamModes, BoundaryConditionsAndTip) {
  for (auto end : kEnds) {
    double alpha[F3R_MAX_MODES], tip[F3R_MAX_MODES];
    f3r_beam_roots(end, F3R_MAX_MODES, alpha);
    f3r_beam_modal_integrals(end, F3R_MAX_MODES, nullptr, nullptr, nullptr, nullptr, tip);
    for (int j = 0; j < F3R_MAX_MODES; ++j) {
      double p0, d0, p1, d1, c1;
      f3r_beam_mode_eval(end, alpha[j], 0.0, &p0, &d0, nullptr);
      f3r_beam_mode_eval(end, alpha[j], 1.0, &p1, &d1, &c1);
      EXPECT_NEAR(p0, 0.0, 1e-13);
      EXPECT_NEAR(d0, 0.0, 1e-13 * alpha[j]);
      EXPECT_NEAR(c1, 0.0, 1e-11 * alpha[j] * alpha[j]) << "zero moment at the tip";
      if (end == F3R_BEAM_FIXED_PINNED) {
        EXPECT_NEAR(p1, 0.0, 1e-13);
        EXPECT_EQ(tip[j], 0.0);
      } else {
        EXPECT_NEAR(tip[j], 2.0 * ((j + 1) % 2 ? -1.0 : 1.0), 1e-12) << "psi_j(1) = 2(-1)^j";
      }
    }
  }
}

TEST(BeamModes, GaussLegendreIsExactForDegree2nMinus1) {
  for (int n : {1, 4, 12, 32}) {
    double x[64], w[64];
    ASSERT_EQ(f3r_gauss_legendre(n, x, w), 0);
    for (int deg = 0; deg <= 2 * n - 1; ++deg) {
      double sum = 0;
      for (int k = 0; k < n; ++k) sum += w[k] * std::pow(x[k], deg);
      EXPECT_NEAR(sum, 1.0 / (deg + 1), 1e-14) << "n " << n << " degree " << deg;
    }
  }
}

TEST(BeamModes, RejectsModeCountsOutsideOneToTwenty) {
  double a[F3R_MAX_MODES + 1];
  EXPECT_EQ(f3r_beam_roots(F3R_BEAM_FIXED_FREE, 0, a), -1);
  EXPECT_EQ(f3r_beam_roots(F3R_BEAM_FIXED_FREE, 21, a), -1);
  EXPECT_EQ(f3r_beam_modal_integrals(F3R_BEAM_FIXED_PINNED, 21, a, nullptr, nullptr, nullptr, nullptr), -1);
}

}  // namespace

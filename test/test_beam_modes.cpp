// Beam modes against independent computations: roots by long-double bisection of the frequency
// equations as printed, the printed (cancelling) mode formulas and their closed-form integrals
// evaluated in 256-bit floating point (MPFR), and polynomial identities for the quadrature.
#include <gtest/gtest.h>
#include <mpfr.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "flex3rpr/beam_modes.h"

namespace {

const f3r_beam_end kEnds[] = {F3R_BEAM_FIXED_PINNED, F3R_BEAM_FIXED_FREE};
constexpr int kR = F3R_MAX_MODES;

// Frequency equations as printed, multiplied by cos a e^-a (tan a = tanh a) or e^-a
// (cos a cosh a + 1 = 0) so they stay finite and continuous.
long double Printed(f3r_beam_end end, long double a) {
  const long double em = expl(-a);
  if (end == F3R_BEAM_FIXED_PINNED)  // (sin a cosh a - cos a sinh a) e^-a
    return sinl(a) * 0.5L * (1 + em * em) - cosl(a) * 0.5L * (1 - em * em);
  return cosl(a) * 0.5L * (1 + em * em) + em;  // (cos a cosh a + 1) e^-a
}

long double Bisect(f3r_beam_end end, long double lo, long double hi) {
  long double flo = Printed(end, lo);
  EXPECT_LT(flo * Printed(end, hi), 0) << "no bracket";
  for (int it = 0; it < 200; ++it) {
    const long double mid = 0.5L * (lo + hi), fm = Printed(end, mid);
    if ((fm < 0) == (flo < 0)) {
      lo = mid;
      flo = fm;
    } else {
      hi = mid;
    }
  }
  return 0.5L * (lo + hi);
}

TEST(BeamModes, RootsMatchBisectionOfThePrintedEquations) {
  const long double pi = 3.141592653589793238462643383279502884L;
  for (auto end : kEnds) {
    double alpha[kR];
    ASSERT_EQ(f3r_beam_roots(end, kR, alpha), 0);
    for (int j = 1; j <= kR; ++j) {
      // One root per window: the scaled equations approach sqrt2 sin(a - pi/4) and cos a.
      const long double mid = end == F3R_BEAM_FIXED_PINNED ? (j + 0.25L) * pi : (j - 0.5L) * pi;
      const long double root = Bisect(end, mid - 0.4L, mid + 0.4L);
      EXPECT_NEAR(alpha[j - 1], static_cast<double>(root), 1e-13) << "end " << end << " mode " << j;
    }
  }
  double a[4];
  ASSERT_EQ(f3r_beam_roots(F3R_BEAM_FIXED_FREE, 4, a), 0);
  // eq. (7), to half a unit of the last printed digit
  EXPECT_NEAR(a[0], 1.875104069, 0.5e-9);
  EXPECT_NEAR(a[1], 4.694091133, 0.5e-9);
  EXPECT_NEAR(a[2], 7.854757438, 0.5e-9);
  EXPECT_NEAR(a[3], 10.99554073, 0.5e-8);
  ASSERT_EQ(f3r_beam_roots(F3R_BEAM_FIXED_PINNED, 3, a), 0);  // docs/model.md
  EXPECT_NEAR(a[0], 3.926602, 0.5e-6);
  EXPECT_NEAR(a[1], 7.068583, 0.5e-6);
  EXPECT_NEAR(a[2], 10.210176, 0.5e-6);
}

// 256-bit numbers: the printed formula loses about a/ln(10) < 28 of their 77 digits.
class Mp {
 public:
  Mp() { mpfr_init2(v_, 256); }
  explicit Mp(double x) : Mp() { mpfr_set_d(v_, x, MPFR_RNDN); }
  Mp(const Mp& o) : Mp() { mpfr_set(v_, o.v_, MPFR_RNDN); }
  Mp& operator=(const Mp& o) {
    mpfr_set(v_, o.v_, MPFR_RNDN);
    return *this;
  }
  ~Mp() { mpfr_clear(v_); }
  mpfr_ptr p() { return v_; }
  mpfr_srcptr p() const { return v_; }
  double d() const { return mpfr_get_d(v_, MPFR_RNDN); }
  friend Mp operator+(const Mp& x, const Mp& y) {
    Mp r;
    mpfr_add(r.v_, x.v_, y.v_, MPFR_RNDN);
    return r;
  }
  friend Mp operator-(const Mp& x, const Mp& y) {
    Mp r;
    mpfr_sub(r.v_, x.v_, y.v_, MPFR_RNDN);
    return r;
  }
  friend Mp operator*(const Mp& x, const Mp& y) {
    Mp r;
    mpfr_mul(r.v_, x.v_, y.v_, MPFR_RNDN);
    return r;
  }
  friend Mp operator/(const Mp& x, const Mp& y) {
    Mp r;
    mpfr_div(r.v_, x.v_, y.v_, MPFR_RNDN);
    return r;
  }
  Mp operator-() const {
    Mp r;
    mpfr_neg(r.v_, v_, MPFR_RNDN);
    return r;
  }

 private:
  mpfr_t v_;
};

using MpFn = int (*)(mpfr_ptr, mpfr_srcptr, mpfr_rnd_t);
Mp Apply(MpFn f, const Mp& x) {
  Mp r;
  f(r.p(), x.p(), MPFR_RNDN);
  return r;
}

// sigma exactly as printed in eqs. (3) and (5), for the double root alpha.
Mp PrintedSigma(f3r_beam_end end, const Mp& a) {
  const Mp c = Apply(mpfr_cos, a), s = Apply(mpfr_sin, a);
  const Mp ch = Apply(mpfr_cosh, a), sh = Apply(mpfr_sinh, a);
  return end == F3R_BEAM_FIXED_FREE ? (c + ch) / (s + sh) : (c - ch) / (s - sh);
}

// psi, psi', psi'' as printed: (cos - cosh) - sigma (sin - sinh) at a xi, differentiated.
void PrintedMode(f3r_beam_end end, double alpha, double xi, double out[3]) {
  const Mp a(alpha), sigma = PrintedSigma(end, a), ax = a * Mp(xi);
  const Mp c = Apply(mpfr_cos, ax), s = Apply(mpfr_sin, ax);
  const Mp ch = Apply(mpfr_cosh, ax), sh = Apply(mpfr_sinh, ax);
  out[0] = ((c - ch) - sigma * (s - sh)).d();
  out[1] = (a * ((-s - sh) - sigma * (c - ch))).d();
  out[2] = (a * a * ((-c - ch) - sigma * (-s + -sh))).d();
}

// int_0^1 psi and int_0^1 xi psi in closed form, from the antiderivatives
//   Psi = ((sin - sinh) + sigma (cos + cosh)) / a,  Phi = (-(cos + cosh) + sigma (sin + sinh)) / a^2,
// int psi = Psi(1) - Psi(0) and int xi psi = Psi(1) - (Phi(1) - Phi(0)) (by parts).
void PrintedMoments(f3r_beam_end end, double alpha, double* mean, double* first) {
  const Mp a(alpha), sigma = PrintedSigma(end, a), one(1.0), two(2.0);
  const Mp c = Apply(mpfr_cos, a), s = Apply(mpfr_sin, a);
  const Mp ch = Apply(mpfr_cosh, a), sh = Apply(mpfr_sinh, a);
  const Mp psi1 = ((s - sh) + sigma * (c + ch)) / a, psi0 = sigma * two / a;
  const Mp phi1 = (-(c + ch) + sigma * (s + sh)) / (a * a), phi0 = -two / (a * a);
  *mean = (psi1 - psi0).d();
  *first = (psi1 - (phi1 - phi0)).d();
}

std::vector<double> SamplePoints() {
  std::vector<double> xi;
  for (int k = 0; k <= 64; ++k) xi.push_back(k / 64.0 + (k % 2 ? 1.0 / 317 : 0.0));
  for (double h = 1e-1; h > 1e-9; h /= 10) {  // the boundary layers at both ends
    xi.push_back(h);
    xi.push_back(1.0 - h);
  }
  return xi;
}

TEST(BeamModes, EvaluationHasNoCancellationUpToMode20) {
  const std::vector<double> xs = SamplePoints();
  for (auto end : kEnds) {
    double alpha[kR];
    ASSERT_EQ(f3r_beam_roots(end, kR, alpha), 0);
    double worst[3] = {0, 0, 0};
    for (int j = 0; j < kR; ++j)
      for (double xi : xs) {
        double ours[3], ref[3];
        f3r_beam_mode_eval(end, alpha[j], xi, &ours[0], &ours[1], &ours[2]);
        PrintedMode(end, alpha[j], xi, ref);
        for (int d = 0; d < 3; ++d) {
          const double err = std::fabs(ours[d] - ref[d]) / std::pow(alpha[j], d);
          worst[d] = std::max(worst[d], err);
          EXPECT_LT(err, 1e-12) << "end " << end << " mode " << j + 1 << " xi " << xi
                                << " derivative " << d << ": " << ours[d] << " vs " << ref[d];
        }
      }
    std::printf("end %d: max |psi^(k) - printed in MPFR| / alpha^k = %.2e %.2e %.2e\n", end,
                worst[0], worst[1], worst[2]);
  }
}

TEST(BeamModes, NullOutputsAreAllowed) {
  double alpha[1], v;
  ASSERT_EQ(f3r_beam_roots(F3R_BEAM_FIXED_FREE, 1, alpha), 0);
  f3r_beam_mode_eval(F3R_BEAM_FIXED_FREE, alpha[0], 0.5, nullptr, nullptr, nullptr);
  f3r_beam_mode_eval(F3R_BEAM_FIXED_FREE, alpha[0], 0.5, nullptr, &v, nullptr);
  EXPECT_TRUE(std::isfinite(v));
  EXPECT_EQ(
      f3r_beam_modal_integrals(F3R_BEAM_FIXED_FREE, 3, nullptr, nullptr, nullptr, nullptr, nullptr),
      0);
}

TEST(BeamModes, OrthonormalAtTwentyModes) {
  for (auto end : kEnds) {
    double gram[kR * kR], bending[kR * kR], alpha[kR];
    ASSERT_EQ(f3r_beam_roots(end, kR, alpha), 0);
    ASSERT_EQ(f3r_beam_modal_integrals(end, kR, nullptr, nullptr, gram, bending, nullptr), 0);
    double worst_norm = 0, worst_off = 0, worst_k = 0;
    for (int i = 0; i < kR; ++i)
      for (int j = 0; j < kR; ++j) {
        const double e = std::fabs(gram[i * kR + j] - (i == j ? 1.0 : 0.0));
        (i == j ? worst_norm : worst_off) = std::max(i == j ? worst_norm : worst_off, e);
        const double scale = alpha[i] * alpha[i] * alpha[j] * alpha[j];
        const double expected = i == j ? scale : 0.0;  // alpha_i^4 delta_ij
        worst_k = std::max(worst_k, std::fabs(bending[i * kR + j] - expected) / scale);
      }
    std::printf(
        "end %d, r = %d: max|int psi_j^2 - 1| = %.2e, max|int psi_i psi_j| = %.2e, "
        "max bending error / (alpha_i alpha_j)^2 = %.2e\n",
        end, kR, worst_norm, worst_off, worst_k);
    EXPECT_LT(worst_norm, 1e-12) << "end " << end;
    EXPECT_LT(worst_off, 1e-12) << "end " << end;
    EXPECT_LT(worst_k, 1e-12) << "end " << end;
  }
}

TEST(BeamModes, MomentsMatchClosedForms) {
  for (auto end : kEnds) {
    double alpha[kR], mean[kR], first[kR];
    ASSERT_EQ(f3r_beam_roots(end, kR, alpha), 0);
    ASSERT_EQ(f3r_beam_modal_integrals(end, kR, mean, first, nullptr, nullptr, nullptr), 0);
    for (int j = 0; j < kR; ++j) {
      double m, f;
      PrintedMoments(end, alpha[j], &m, &f);
      EXPECT_NEAR(mean[j], m, 1e-13) << "end " << end << " mode " << j + 1;
      EXPECT_NEAR(first[j], f, 1e-13) << "end " << end << " mode " << j + 1;
    }
  }
}

// The model's constants (closed form, double) against the quadrature and the printed forms in
// multiple precision; the stiffness alpha^4 against the quadrature's int psi''^2.
TEST(BeamModes, ModelConstantsMatchQuadratureAndPrintedForms) {
  for (auto end : kEnds) {
    double alpha[kR], mean[kR], first[kR], tip[kR];
    double q_mean[kR], q_first[kR], q_tip[kR], bending[kR * kR];
    ASSERT_EQ(f3r_beam_mode_constants(end, kR, alpha, mean, first, tip), 0);
    ASSERT_EQ(f3r_beam_modal_integrals(end, kR, q_mean, q_first, nullptr, bending, q_tip), 0);
    for (int j = 0; j < kR; ++j) {
      double m, f;
      PrintedMoments(end, alpha[j], &m, &f);
      EXPECT_NEAR(mean[j], m, 1e-14) << "end " << end << " mode " << j + 1;
      EXPECT_NEAR(first[j], f, 1e-14) << "end " << end << " mode " << j + 1;
      EXPECT_NEAR(mean[j], q_mean[j], 1e-14) << "end " << end << " mode " << j + 1;
      EXPECT_NEAR(first[j], q_first[j], 1e-14) << "end " << end << " mode " << j + 1;
      EXPECT_EQ(tip[j], q_tip[j]) << "end " << end << " mode " << j + 1;
      const double a4 = std::pow(alpha[j], 4);
      EXPECT_NEAR(bending[j * kR + j] / a4, 1.0, 1e-12) << "end " << end << " mode " << j + 1;
    }
  }
  double alpha[1];
  EXPECT_EQ(f3r_beam_mode_constants(F3R_BEAM_FIXED_FREE, 0, alpha, nullptr, nullptr, nullptr), -1);
  EXPECT_EQ(f3r_beam_mode_constants(F3R_BEAM_FIXED_FREE, kR + 1, alpha, nullptr, nullptr, nullptr),
            -1);
}

TEST(BeamModes, FewerModesGiveTheLeadingBlock) {
  for (auto end : kEnds) {
    const int r = 5;
    double g20[kR * kR], g5[r * r], m20[kR], m5[r];
    ASSERT_EQ(f3r_beam_modal_integrals(end, kR, m20, nullptr, g20, nullptr, nullptr), 0);
    ASSERT_EQ(f3r_beam_modal_integrals(end, r, m5, nullptr, g5, nullptr, nullptr), 0);
    for (int i = 0; i < r; ++i) {
      EXPECT_EQ(m5[i], m20[i]);
      for (int j = 0; j < r; ++j) EXPECT_EQ(g5[i * r + j], g20[i * kR + j]);
    }
  }
}

TEST(BeamModes, BoundaryConditionsAndTip) {
  for (auto end : kEnds) {
    double alpha[kR], tip[kR];
    ASSERT_EQ(f3r_beam_roots(end, kR, alpha), 0);
    ASSERT_EQ(f3r_beam_modal_integrals(end, kR, nullptr, nullptr, nullptr, nullptr, tip), 0);
    for (int j = 0; j < kR; ++j) {
      const double a = alpha[j];
      double p0, d0, p1, d1, c1;
      f3r_beam_mode_eval(end, a, 0.0, &p0, &d0, nullptr);
      f3r_beam_mode_eval(end, a, 1.0, &p1, &d1, &c1);
      EXPECT_NEAR(p0, 0.0, 1e-13) << "clamped: deflection, mode " << j + 1;
      EXPECT_NEAR(d0, 0.0, 1e-13 * a) << "clamped: slope, mode " << j + 1;
      EXPECT_NEAR(c1, 0.0, 1e-12 * a * a) << "no moment at the tip, mode " << j + 1;
      EXPECT_GT(std::fabs(d1), 0.1 * a) << "tip slope is free, mode " << j + 1;
      if (end == F3R_BEAM_FIXED_PINNED) {
        EXPECT_NEAR(p1, 0.0, 1e-13) << "pinned, mode " << j + 1;
        EXPECT_EQ(tip[j], 0.0);
      } else {
        const double sign = (j + 1) % 2 ? -1.0 : 1.0;
        EXPECT_NEAR(tip[j], 2.0 * sign, 1e-12) << "psi_j(1) = 2(-1)^j, mode " << j + 1;
        EXPECT_EQ(tip[j], p1);
        // No shear at a free tip: psi'''(1) = 0, from psi'' by a 4th-order one-sided difference
        // (truncation ~ (h a)^4 a^3, rounding ~ 1e-14 a^3 for h = 0.01/a).
        const double h = 0.01 / a;
        double f[5];
        for (int k = 0; k < 5; ++k)
          f3r_beam_mode_eval(end, a, 1.0 - k * h, nullptr, nullptr, &f[k]);
        const double d3 = (25 * f[0] - 48 * f[1] + 36 * f[2] - 16 * f[3] + 3 * f[4]) / (12 * h);
        EXPECT_NEAR(d3, 0.0, 1e-6 * a * a * a) << "no shear at the free tip, mode " << j + 1;
      }
    }
  }
}

TEST(BeamModes, GaussLegendreIsExactForDegree2nMinus1) {
  for (int n = 1; n <= 64; ++n) {
    double x[64], w[64];
    ASSERT_EQ(f3r_gauss_legendre(n, x, w), 0);
    for (int k = 0; k < n; ++k) {
      EXPECT_GT(w[k], 0.0);
      EXPECT_GT(x[k], k ? x[k - 1] : 0.0) << "nodes increasing inside (0, 1), n " << n;
      EXPECT_LT(x[k], 1.0);
    }
    for (int deg = 0; deg <= 2 * n; ++deg) {
      long double sum = 0;
      for (int k = 0; k < n; ++k) sum += w[k] * std::pow(static_cast<long double>(x[k]), deg);
      const double err = std::fabs(static_cast<double>(sum) - 1.0 / (deg + 1));
      if (deg < 2 * n) {
        EXPECT_LT(err, 2e-15) << "n " << n << " degree " << deg;
      } else if (n <= 4) {  // and not beyond: degree 2n is off by n!^4 / ((2n+1) (2n)!^2)
        EXPECT_GT(err, 1e-6) << "n " << n << " degree " << deg;
      }
    }
  }
}

TEST(BeamModes, RejectsBadCounts) {
  double a[kR + 2], x[65], w[65];
  for (int bad : {-1, 0, kR + 1}) {
    EXPECT_EQ(f3r_beam_roots(F3R_BEAM_FIXED_FREE, bad, a), -1) << bad;
    EXPECT_EQ(f3r_beam_roots(F3R_BEAM_FIXED_PINNED, bad, a), -1) << bad;
    EXPECT_EQ(
        f3r_beam_modal_integrals(F3R_BEAM_FIXED_PINNED, bad, a, nullptr, nullptr, nullptr, nullptr),
        -1)
        << bad;
    EXPECT_EQ(
        f3r_beam_modal_integrals(F3R_BEAM_FIXED_FREE, bad, nullptr, nullptr, nullptr, nullptr, a),
        -1)
        << bad;
  }
  EXPECT_EQ(f3r_gauss_legendre(0, x, w), -1);
  EXPECT_EQ(f3r_gauss_legendre(65, x, w), -1);
}

}  // namespace

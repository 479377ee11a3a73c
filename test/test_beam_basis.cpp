// The static-correction beam basis (src/core/physics/beam_basis.h, issue 28) against independent
// computations: quadrature of f3r_beam_basis_eval on a rule other than the build's, the paper's
// modes bit for bit, 50-digit reference values, and a beam with a tip mass whose frequency
// equation is solved here in long double.
//
// The literals marked "reference" are the doubles nearest the 50-digit values computed by
// test/reference/static_correction_reference.py (mpmath, an independent derivation of the closed
// forms and the Ritz step, each checked there against mp.quad to 1e-30; the script writes them to
// reference_values.json next to itself).
#include <gtest/gtest.h>
#include <mpfr.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "beam_basis.h"
#include "flex3rpr/beam_modes.h"

namespace {

const f3r_beam_end kEnds[] = {F3R_BEAM_FIXED_PINNED, F3R_BEAM_FIXED_FREE};
constexpr unsigned kTip = F3R_SHAPE_TIP_FORCE, kUniform = F3R_SHAPE_UNIFORM_LOAD,
                   kLinear = F3R_SHAPE_LINEAR_LOAD;
constexpr double kEps = 2.220446049250313e-16;

std::vector<unsigned> ShapeSets(f3r_beam_end end) {
  if (end == F3R_BEAM_FIXED_PINNED) return {kUniform, kLinear, kUniform | kLinear};
  return {kTip,
          kUniform,
          kLinear,
          kTip | kUniform,
          kTip | kLinear,
          kUniform | kLinear,
          kTip | kUniform | kLinear};
}

// 192-bit evaluation of the functions the stored basis defines (alpha, V, CV): the modes in the
// printed, cancelling form (eq. 3-6), which loses alpha / ln 10 < 15 of its 57 digits for r <= 10,
// and the shapes' polynomials. It separates the basis' own error from the rounding of
// f3r_beam_basis_eval, which cancels |s| / |t| in doubles.
class Mp {
 public:
  Mp() { mpfr_init2(v_, 192); }
  explicit Mp(double x) : Mp() { mpfr_set_d(v_, x, MPFR_RNDN); }
  Mp(const Mp& o) : Mp() { mpfr_set(v_, o.v_, MPFR_RNDN); }
  Mp& operator=(const Mp& o) {
    mpfr_set(v_, o.v_, MPFR_RNDN);
    return *this;
  }
  ~Mp() { mpfr_clear(v_); }
  mpfr_ptr p() { return v_; }
  mpfr_srcptr p() const { return v_; }
  long double ld() const { return mpfr_get_ld(v_, MPFR_RNDN); }

 private:
  mpfr_t v_;
};

Mp Op(int (*f)(mpfr_ptr, mpfr_srcptr, mpfr_srcptr, mpfr_rnd_t), const Mp& x, const Mp& y) {
  Mp r;
  f(r.p(), x.p(), y.p(), MPFR_RNDN);
  return r;
}
Mp operator+(const Mp& x, const Mp& y) { return Op(mpfr_add, x, y); }
Mp operator-(const Mp& x, const Mp& y) { return Op(mpfr_sub, x, y); }
Mp operator*(const Mp& x, const Mp& y) { return Op(mpfr_mul, x, y); }
Mp operator/(const Mp& x, const Mp& y) { return Op(mpfr_div, x, y); }
Mp MpL(long double x) {
  Mp r;
  mpfr_set_ld(r.p(), x, MPFR_RNDN);
  return r;
}
Mp Fn(int (*f)(mpfr_ptr, mpfr_srcptr, mpfr_rnd_t), const Mp& x) {
  Mp r;
  f(r.p(), x.p(), MPFR_RNDN);
  return r;
}

// psi_j and psi_j'' as printed, for the double root alpha.
void PrintedMode(f3r_beam_end end, double alpha, const Mp& xi, Mp* psi, Mp* ddpsi) {
  const Mp a(alpha), ax = a * xi;
  const Mp c = Fn(mpfr_cos, a), s = Fn(mpfr_sin, a), ch = Fn(mpfr_cosh, a), sh = Fn(mpfr_sinh, a);
  const Mp sigma = end == F3R_BEAM_FIXED_FREE ? (c + ch) / (s + sh) : (c - ch) / (s - sh);
  const Mp cx = Fn(mpfr_cos, ax), sx = Fn(mpfr_sin, ax);
  const Mp chx = Fn(mpfr_cosh, ax), shx = Fn(mpfr_sinh, ax);
  *psi = (cx - chx) - sigma * (sx - shx);
  *ddpsi = a * a * ((Mp(0.0) - cx - chx) + sigma * (sx + shx));
}

// The shapes' polynomial coefficients (beam_basis.h), as exact rationals num/den.
void Shape(f3r_beam_end end, unsigned kind, const Mp& xi, Mp* s, Mp* dds) {
  static const double kFree[3][4][2] = {// {num, den} of xi^2, xi^3, xi^4, xi^5
                                        {{1, 2}, {-1, 6}, {0, 1}, {0, 1}},
                                        {{1, 4}, {-1, 6}, {1, 24}, {0, 1}},
                                        {{1, 6}, {-1, 12}, {0, 1}, {1, 120}}};
  static const double kPinned[2][4][2] = {{{1, 16}, {-5, 48}, {1, 24}, {0, 1}},
                                          {{7, 240}, {-3, 80}, {0, 1}, {1, 120}}};
  const int index = kind == kTip ? 0 : kind == kUniform ? 1 : 2;
  const double(*c)[2] = end == F3R_BEAM_FIXED_FREE ? kFree[index] : kPinned[index - 1];
  *s = Mp(0.0);
  *dds = Mp(0.0);
  Mp power(1.0);  // xi^(a - 2)
  for (int a = 2; a <= 5; ++a) {
    const Mp coef = Mp(c[a - 2][0]) / Mp(c[a - 2][1]);
    *dds = *dds + coef * Mp(a * (a - 1.0)) * power;
    *s = *s + coef * power * xi * xi;
    power = power * xi;
  }
}

// The Gram matrices of the stored basis, by 80 x 10 Gauss-Legendre in 192 bits.
void ExactGrams(const f3r_beam_basis& b, Eigen::MatrixXd* mass, Eigen::MatrixXd* bending) {
  const int n = b.count, r = b.modes, panels = 80, points = 10;
  double x[points], w[points];
  f3r_gauss_legendre(points, x, w);
  std::vector<std::vector<Mp>> gm(n, std::vector<Mp>(n, Mp(0.0))), gk = gm;
  for (int p = 0; p < panels; ++p)
    for (int q = 0; q < points; ++q) {
      const Mp xi = (Mp(p) + Mp(x[q])) / Mp(panels), wq = Mp(w[q]) / Mp(panels);
      std::vector<Mp> phi(n), dd(n);
      for (int j = 0; j < r; ++j) PrintedMode(b.end, b.alpha[j], xi, &phi[j], &dd[j]);
      for (int m = 0; m < b.corrections; ++m) {
        phi[r + m] = Mp(0.0);
        dd[r + m] = Mp(0.0);
        for (int k = 0; k < b.shapes; ++k) {
          Mp s, sdd;
          Shape(b.end, b.shape_kind[k], xi, &s, &sdd);
          phi[r + m] = phi[r + m] + MpL(b.V[k][m]) * s;
          dd[r + m] = dd[r + m] + MpL(b.V[k][m]) * sdd;
        }
        for (int j = 0; j < r; ++j) {
          phi[r + m] = phi[r + m] - MpL(b.CV[j][m]) * phi[j];
          dd[r + m] = dd[r + m] - MpL(b.CV[j][m]) * dd[j];
        }
      }
      for (int i = 0; i < n; ++i)
        for (int j = i; j < n; ++j) {
          gm[i][j] = gm[i][j] + wq * phi[i] * phi[j];
          gk[i][j] = gk[i][j] + wq * dd[i] * dd[j];
        }
    }
  mass->resize(n, n);
  bending->resize(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = i; j < n; ++j) {
      (*mass)(i, j) = (*mass)(j, i) = static_cast<double>(gm[i][j].ld());
      (*bending)(i, j) = (*bending)(j, i) = static_cast<double>(gk[i][j].ld());
    }
}

// The basis' Gram matrices and constants by composite Gauss-Legendre quadrature of
// f3r_beam_basis_eval: 80 panels of 10 points (the build uses 64 of 12).
struct Quadrature {
  Eigen::MatrixXd mass, bending;
  Eigen::VectorXd mean, first_moment;
};

Quadrature Integrate(const f3r_beam_basis& b) {
  const int n = b.count, panels = 80, points = 10;
  double x[points], w[points];
  EXPECT_EQ(f3r_gauss_legendre(points, x, w), 0);
  Quadrature q{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(n, n), Eigen::VectorXd::Zero(n),
               Eigen::VectorXd::Zero(n)};
  Eigen::VectorXd phi(n), curv(n);
  for (int p = 0; p < panels; ++p)
    for (int k = 0; k < points; ++k) {
      const double xi = (p + x[k]) / panels, wk = w[k] / panels;
      for (int j = 0; j < n; ++j) f3r_beam_basis_eval(&b, j, xi, &phi[j], nullptr, &curv[j]);
      q.mass += wk * phi * phi.transpose();
      q.bending += wk * curv * curv.transpose();
      q.mean += wk * phi;
      q.first_moment += wk * xi * phi;
    }
  return q;
}

// The smallest residual ratio ||t_k|| / ||s_k|| of the kept shapes (1 if none): the rounding of
// every correction is about eps / ratio (the cancellation in s_k - sum C psi).
double MinRatio(const f3r_beam_basis& b) {
  double r = 1.0;
  for (int k = 0; k < b.shapes; ++k) r = std::min(r, b.residual_ratio[k]);
  return r;
}

struct Orthogonality {
  double mass = 0, bending = 0;  // max |M - I|, max |K - diag| / sqrt(k_i k_j)
};

Orthogonality Deviation(const f3r_beam_basis& b, const Eigen::MatrixXd& mass,
                        const Eigen::MatrixXd& bending) {
  Orthogonality o;
  for (int i = 0; i < b.count; ++i)
    for (int j = 0; j < b.count; ++j) {
      o.mass = std::max(o.mass, std::fabs(mass(i, j) - (i == j ? 1.0 : 0.0)));
      const double expected = i == j ? b.stiffness[i] : 0.0;
      o.bending = std::max(o.bending, std::fabs(bending(i, j) - expected) /
                                          std::sqrt(b.stiffness[i] * b.stiffness[j]));
    }
  return o;
}

Orthogonality Check(const f3r_beam_basis& b) {
  const Quadrature q = Integrate(b);
  return Deviation(b, q.mass, q.bending);
}

Orthogonality CheckExact(const f3r_beam_basis& b) {
  Eigen::MatrixXd mass, bending;
  ExactGrams(b, &mass, &bending);
  return Deviation(b, mass, bending);
}

TEST(BeamBasis, OrthonormalWithDiagonalStiffness) {
  for (auto end : kEnds)
    for (unsigned set : ShapeSets(end))
      for (int r = 1; r <= 5; ++r) {
        f3r_beam_basis b;
        ASSERT_EQ(f3r_beam_basis_build(end, r, set, &b), 0);
        const Orthogonality o = Check(b), e = CheckExact(b);
        // the cancellation in V s - CV psi, in long double: eps_ld / ratio, times a measured 40
        const double bound = r <= 3 ? 1e-12 : 5e-12;
        std::printf(
            "end %d r %d set %u: shapes %d, min ratio %.1e, max|M - I| %.1e, "
            "max|K - diag|/k %.1e; 192-bit: %.1e, %.1e\n",
            end, r, set, b.shapes, MinRatio(b), o.mass, o.bending, e.mass, e.bending);
        EXPECT_LT(o.mass, bound) << "end " << end << " r " << r << " set " << set;
        EXPECT_LT(o.bending, 1e-12) << "end " << end << " r " << r << " set " << set;
        EXPECT_LT(e.mass, bound) << "end " << end << " r " << r << " set " << set;
        EXPECT_LT(e.bending, 1e-12) << "end " << end << " r " << r << " set " << set;
      }
}

// r = 6..20 (as far as r plus the shapes fit): the build drops the shapes whose residual is below
// 1e-6 of themselves, so the cancellation stays bounded. Measured worst over r and sets: 4.4e-13
// and 3.0e-14 (fixed-pinned); at r = 10, 4.2e-13 and 1.3e-14.
TEST(BeamBasis, OrthonormalUpToTwentyFunctions) {
  for (auto end : kEnds)
    for (unsigned set : ShapeSets(end)) {
      Orthogonality worst;
      int last = 0;
      for (int r = 6; r <= F3R_MAX_MODES; ++r) {
        f3r_beam_basis b;
        const int asked = (set & 1) + (set >> 1 & 1) + (set >> 2 & 1);
        ASSERT_EQ(f3r_beam_basis_build(end, r, set, &b), r + asked <= F3R_MAX_MODES ? 0 : -1);
        if (r + asked > F3R_MAX_MODES) continue;
        last = r;
        const Orthogonality o = Check(b);
        EXPECT_LT(o.mass, 2e-12) << "end " << end << " r " << r << " set " << set;
        EXPECT_LT(o.bending, 2e-13) << "end " << end << " r " << r << " set " << set;
        worst.mass = std::max(worst.mass, o.mass);
        worst.bending = std::max(worst.bending, o.bending);
        if (r == 10)
          std::printf(
              "end %d r 10 set %u: shapes %d, min ratio %.1e, max|M - I| %.1e, "
              "max|K - diag|/k %.1e\n",
              end, set, b.shapes, MinRatio(b), o.mass, o.bending);
      }
      std::printf("end %d set %u, r = 6..%d: max|M - I| %.1e, max|K - diag|/k %.1e\n", end, set,
                  last, worst.mass, worst.bending);
    }
}

// Reference: the per-function constants of the corrected bases (reference_values.json "bases").
struct Reference {
  f3r_beam_end end;
  int r;
  unsigned set;
  int m;
  double stiffness, mean, first_moment, tip, tip_slope;
};
const Reference kReference[] = {
    // {end, r, shape set, m, stiffness, mean, first_moment, tip, tip_slope}
    {F3R_BEAM_FIXED_FREE, 1, 1, 0, 565.8654036074379, -0.40273068511949356, -0.08633219430981913,
     2.3513503061059033, 13.143191720961916},
    {F3R_BEAM_FIXED_FREE, 1, 3, 0, 492.6071020144893, -0.4406658483298998, -0.09146685151558506,
     2.026951447439909, 10.054268089153785},
    {F3R_BEAM_FIXED_FREE, 1, 3, 1, 4262.261971009444, 0.241256266116972, 0.030425986068870977,
     2.4690049468442896, 22.862192994367014},
    {F3R_BEAM_FIXED_FREE, 1, 7, 0, 485.85355802521445, -0.43432658328832685, -0.09084092071525883,
     2.0006906263822004, 9.624205610512115},
    {F3R_BEAM_FIXED_FREE, 1, 7, 1, 4129.451583744426, 0.2663066708684496, 0.03301706489758149,
     2.22438108819798, 19.746224664320085},
    {F3R_BEAM_FIXED_FREE, 1, 7, 2, 17116.447935494725, -0.20347594870421332, -0.017543913332095006,
     2.390270383212166, 31.12246709095986},
    {F3R_BEAM_FIXED_FREE, 2, 1, 0, 5141.1039398591865, 0.20890944472372003, 0.02776851045871304,
     2.8064489909171617, 27.894481224513836},
    {F3R_BEAM_FIXED_FREE, 2, 3, 0, 4027.470093766022, 0.27120920846566404, 0.03366056958442673,
     2.103637196095191, 18.048682225697934},
    {F3R_BEAM_FIXED_FREE, 2, 3, 1, 17212.209284919834, -0.17408394370292632, -0.0152744153886513,
     2.730692679243402, 36.55839075857292},
    {F3R_BEAM_FIXED_FREE, 2, 7, 0, 3829.947488610657, 0.25686824189600077, 0.032693377979181176,
     2.0037899458296637, 16.11273838854065},
    {F3R_BEAM_FIXED_FREE, 2, 7, 1, 17020.892880314554, -0.19142612686915775, -0.0166111446057455,
     2.5394222924903165, 33.46627773456421},
    {F3R_BEAM_FIXED_FREE, 2, 7, 2, 52299.131523864904, 0.183417114311909, 0.011882826094341123,
     2.340770309166171, 40.309823932185246},
    {F3R_BEAM_FIXED_FREE, 3, 1, 0, 21937.90520405009, -0.13259534563751693, -0.012650321049844183,
     3.248997819726728, 47.127834088336954},
    {F3R_BEAM_FIXED_FREE, 3, 3, 0, 16300.59884671719, -0.2073844849276203, -0.01801116181645768,
     2.200767278932164, 27.61146073275294},
    {F3R_BEAM_FIXED_FREE, 3, 3, 1, 49669.36852384867, 0.13736851275219286, 0.009170071934658347,
     3.0234906112425075, 53.41927958819608},
    {F3R_BEAM_FIXED_FREE, 3, 7, 0, 14894.513972621799, -0.1879809609003924, -0.017034448763712965,
     2.0068996797677476, 23.13550076297061},
    {F3R_BEAM_FIXED_FREE, 3, 7, 1, 49575.56801214878, 0.14499236628303727, 0.009628248090638116,
     2.931342903702048, 51.597072568254276},
    {F3R_BEAM_FIXED_FREE, 3, 7, 2, 132655.4219480538, -0.17154516849032547, -0.008784848728962603,
     2.2285188785171757, 48.30259990816283},
    {F3R_BEAM_FIXED_PINNED, 1, 2, 0, 6716.099615959299, 0.3042621471658567, -0.006428329656162909,
     0.0, -3.8870738853187334},
    {F3R_BEAM_FIXED_PINNED, 1, 6, 0, 2565.7544833782754, 0.08500497913709722, -0.164909139762873,
     0.0, 11.113454410537265},
    {F3R_BEAM_FIXED_PINNED, 1, 6, 1, 11487.521591357827, 0.35495541233191313, 0.1673930214952056,
     0.0, -17.615108617447476},
    {F3R_BEAM_FIXED_PINNED, 2, 2, 0, 11547.305114260487, 0.35719370645094206, 0.16209142226798665,
     0.0, -16.376416551200258},
    {F3R_BEAM_FIXED_PINNED, 2, 6, 0, 11487.501679817498, 0.3548961125756271, 0.16750621272582442,
     0.0, -17.63892625115351},
    {F3R_BEAM_FIXED_PINNED, 2, 6, 1, 35236.300260237644, 0.05469601674328207, -0.10369897239957179,
     0.0, 24.716096869326563},
    {F3R_BEAM_FIXED_PINNED, 3, 2, 0, 75159.45506440554, 0.23905327121042597, 0.050953279847862715,
     0.0, -19.575806643979462},
    {F3R_BEAM_FIXED_PINNED, 3, 6, 0, 35219.76018327968, 0.04908686138294783, -0.10626281646705875,
     0.0, 25.400643792059476},
    {F3R_BEAM_FIXED_PINNED, 3, 6, 1, 84651.00535605311, 0.2420163934979542, 0.10848743224256338,
     0.0, -34.16057779005398},
};

TEST(BeamBasis, ConstantsMatchTheReferenceAndQuadrature) {
  double worst_ref = 0, worst_quad = 0;
  for (const Reference& ref : kReference) {
    f3r_beam_basis b;
    ASSERT_EQ(f3r_beam_basis_build(ref.end, ref.r, ref.set, &b), 0);
    const int f = ref.r + ref.m;
    ASSERT_LT(f, b.count);
    double slope;
    f3r_beam_basis_eval(&b, f, 1.0, nullptr, &slope, nullptr);
    const double ours[5] = {b.stiffness[f], b.mean[f], b.first_moment[f], b.tip[f], slope};
    const double theirs[5] = {ref.stiffness, ref.mean, ref.first_moment, ref.tip, ref.tip_slope};
    for (int c = 0; c < 5; ++c) {
      // Relative to max(|value|, 1e-2): the smallest first moments are ~1e-2. The reference's
      // functions are built on the exact roots, ours on the double roots: 1e-16 in a root,
      // times |CV| (1e7 at r = 3 with three shapes), shows as up to 1.4e-11.
      const double err = std::fabs(ours[c] - theirs[c]) / std::max(std::fabs(theirs[c]), 1e-2);
      worst_ref = std::max(worst_ref, err);
      EXPECT_LT(err, ref.r == 3 && ref.set == 7 ? 5e-11 : 5e-12)
          << "end " << ref.end << " r " << ref.r << " set " << ref.set << " m " << ref.m
          << " constant " << c;
    }
    if (ref.end == F3R_BEAM_FIXED_PINNED) {
      EXPECT_EQ(b.tip[f], 0.0);
    }
  }
  for (auto end : kEnds)
    for (unsigned set : ShapeSets(end))
      for (int r : {1, 2, 3, 4, 5, 10}) {
        f3r_beam_basis b;
        ASSERT_EQ(f3r_beam_basis_build(end, r, set, &b), 0);
        const Quadrature q = Integrate(b);
        for (int j = 0; j < b.count; ++j) {
          double tip;
          f3r_beam_basis_eval(&b, j, 1.0, &tip, nullptr, nullptr);
          const double err = std::max({std::fabs(q.mean[j] - b.mean[j]),
                                       std::fabs(q.first_moment[j] - b.first_moment[j]),
                                       std::fabs(tip - b.tip[j])});
          worst_quad = std::max(worst_quad, err);
          // long double cancellation in V s - CV psi: eps_ld |V| reaches 1e-12 at r = 5
          EXPECT_LT(err, r <= 3 ? 2e-13 : 3e-12)
              << "end " << end << " r " << r << " set " << set << " j " << j;
        }
      }
  std::printf(
      "worst constant against the 50-digit reference %.1e (relative), against "
      "quadrature of the functions %.1e (absolute)\n",
      worst_ref, worst_quad);
}

// The derivation's closed form of the couplings, sign conventions included:
// int psi_j s_k = (F tip_j + q0 mean_j + q1 first_moment_j) / alpha_j^4, against quadrature.
TEST(BeamBasis, CouplingClosedFormMatchesQuadrature) {
  struct Shape {
    f3r_beam_end end;
    double c2, c3, c4, c5, F, q0, q1;
  };
  const Shape shapes[] = {{F3R_BEAM_FIXED_FREE, 1.0 / 2, -1.0 / 6, 0, 0, 1, 0, 0},
                          {F3R_BEAM_FIXED_FREE, 1.0 / 4, -1.0 / 6, 1.0 / 24, 0, 0, 1, 0},
                          {F3R_BEAM_FIXED_FREE, 1.0 / 6, -1.0 / 12, 0, 1.0 / 120, 0, 0, 1},
                          {F3R_BEAM_FIXED_PINNED, 1.0 / 16, -5.0 / 48, 1.0 / 24, 0, 0, 1, 0},
                          {F3R_BEAM_FIXED_PINNED, 7.0 / 240, -3.0 / 80, 0, 1.0 / 120, 0, 0, 1}};
  double x[10], w[10];
  ASSERT_EQ(f3r_gauss_legendre(10, x, w), 0);
  for (const Shape& s : shapes) {
    double alpha[10], mean[10], first[10], tip[10];
    ASSERT_EQ(f3r_beam_mode_constants(s.end, 10, alpha, mean, first, tip), 0);
    for (int j = 0; j < 10; ++j) {
      long double quad = 0;
      for (int p = 0; p < 80; ++p)
        for (int k = 0; k < 10; ++k) {
          const double xi = (p + x[k]) / 80;
          double psi;
          f3r_beam_mode_eval(s.end, alpha[j], xi, &psi, nullptr, nullptr);
          const double shape = xi * xi * (s.c2 + xi * (s.c3 + xi * (s.c4 + xi * s.c5)));
          quad += w[k] / 80 * psi * shape;
        }
      const double closed =
          (s.F * tip[j] + s.q0 * mean[j] + s.q1 * first[j]) / std::pow(alpha[j], 4);
      EXPECT_NEAR(closed, static_cast<double>(quad), 2e-16) << "end " << s.end << " mode " << j + 1;
    }
  }
}

TEST(BeamBasis, NoShapesIsThePapersBasisBitForBit) {
  for (auto end : kEnds)
    for (int r = 1; r <= F3R_MAX_MODES; ++r) {
      double alpha[F3R_MAX_MODES], mean[F3R_MAX_MODES], first[F3R_MAX_MODES], tip[F3R_MAX_MODES];
      ASSERT_EQ(f3r_beam_mode_constants(end, r, alpha, mean, first, tip), 0);
      for (unsigned set : {0u, kUniform, kUniform | kLinear}) {
        if (r + 2 > F3R_MAX_MODES && set) continue;
        f3r_beam_basis b;
        ASSERT_EQ(f3r_beam_basis_build(end, r, set, &b), 0);
        EXPECT_EQ(b.modes, r);
        if (!set) {
          EXPECT_EQ(b.count, r);
          EXPECT_EQ(b.shapes, 0);
        }
        for (int j = 0; j < r; ++j) {  // EXPECT_EQ on doubles: bit for bit
          EXPECT_EQ(b.alpha[j], alpha[j]);
          EXPECT_EQ(b.mean[j], mean[j]);
          EXPECT_EQ(b.first_moment[j], first[j]);
          EXPECT_EQ(b.tip[j], tip[j]);
          const double a2 = alpha[j] * alpha[j];
          EXPECT_EQ(b.stiffness[j], a2 * a2);  // as model.c
          double p[3], q[3];
          f3r_beam_basis_eval(&b, j, 0.37, &p[0], &p[1], &p[2]);
          f3r_beam_mode_eval(end, alpha[j], 0.37, &q[0], &q[1], &q[2]);
          for (int d = 0; d < 3; ++d) EXPECT_EQ(p[d], q[d]);
        }
      }
    }
}

TEST(BeamBasis, CorrectionsAreSortedSignedAndAboveTheKeptModes) {
  for (auto end : kEnds)
    for (unsigned set : ShapeSets(end))
      for (int r = 1; r <= 12; ++r) {
        f3r_beam_basis b;
        ASSERT_EQ(f3r_beam_basis_build(end, r, set, &b), 0);
        for (int m = 0; m < b.shapes; ++m) {
          const int f = r + m;
          // lambda_1 >= alpha_{r+1}^4: the Rayleigh quotient on the complement of the kept modes
          double next[F3R_MAX_MODES];
          ASSERT_EQ(f3r_beam_roots(end, r + 1, next), 0);
          EXPECT_GT(b.stiffness[f], std::pow(next[r], 4) * (1 - 1e-12));
          if (m) {
            EXPECT_GT(b.stiffness[f], b.stiffness[f - 1]);
          }
          EXPECT_GT(end == F3R_BEAM_FIXED_FREE ? b.tip[f] : b.mean[f], 0.0);
          EXPECT_NEAR(b.alpha[f], std::pow(b.stiffness[f], 0.25), 1e-13 * b.alpha[f]);
        }
      }
}

// Reference "trap": ||t_k|| / ||s_k|| and the Ritz eigenvalues of all requested shapes (no drop).
struct Trap {
  f3r_beam_end end;
  int r;
  unsigned set;
  double ratio[3], lambda[3];
};
const Trap kTrap[] = {
    {F3R_BEAM_FIXED_FREE,
     15,
     7,
     {3.6496638781213112e-06, 1.7396488004868173e-07, 4.5793307067759695e-09},
     {6770313.230045601, 12520478.15963244, 30578722.86183337}},
    {F3R_BEAM_FIXED_FREE,
     15,
     3,
     {3.6496638781213112e-06, 1.7396488004868173e-07},
     {8685234.941990651, 12614910.939803343}},
    {F3R_BEAM_FIXED_PINNED,
     15,
     6,
     {2.579702700075431e-06, 3.075988451762025e-06},
     {9914480.8321641, 12674745.381168714}},
    {F3R_BEAM_FIXED_FREE,
     3,
     7,
     {0.000915129524376743, 0.00020554165156447563, 2.5252262129160383e-05},
     {14894.513972621799, 49575.56801214878, 132655.4219480538}},
    {F3R_BEAM_FIXED_FREE,
     6,
     7,
     {8.784762571246623e-05, 1.0310303232367304e-05, 6.661922356752065e-07},
     {187610.23793527752, 437560.28982890566, 1058024.1371200487}},
    {F3R_BEAM_FIXED_FREE,
     10,
     7,
     {1.4990446902649663e-05, 1.0677543247978727e-06, 4.196619033588972e-08},
     {1360711.6689849554, 2705397.0552962725, 6544107.196776092}},
    {F3R_BEAM_FIXED_FREE,
     12,
     7,
     {7.946788955596612e-06, 4.726775825829151e-07, 1.552044920542405e-08},
     {2793872.7395602716, 5349254.035828574, 12995623.606780205}},
    {F3R_BEAM_FIXED_FREE,
     20,
     7,
     {1.3364191521799291e-06, 4.784090790525992e-08, 9.460654171129007e-10},
     {21286532.055730194, 38200438.16585851, 93812152.99265587}},
    {F3R_BEAM_FIXED_FREE,
     3,
     3,
     {0.000915129524376743, 0.00020554165156447563},
     {16300.59884671719, 49669.36852384867}},
    {F3R_BEAM_FIXED_FREE,
     10,
     3,
     {1.4990446902649663e-05, 1.0677543247978727e-06},
     {1700989.9662569559, 2727631.8898362396}},
    {F3R_BEAM_FIXED_FREE,
     20,
     3,
     {1.3364191521799291e-06, 4.784090790525992e-08},
     {27639654.49178737, 38419471.48661933}},
    {F3R_BEAM_FIXED_PINNED,
     3,
     6,
     {0.0008791151814588456, 0.001622676921768457},
     {35219.76018327968, 84651.00535605311}},
    {F3R_BEAM_FIXED_PINNED,
     6,
     6,
     {0.00016236819728891277, 0.000140882580837325},
     {330099.3613946459, 573651.9247893617}},
    {F3R_BEAM_FIXED_PINNED,
     10,
     6,
     {1.9364289615921627e-05, 1.7421044244881814e-05},
     {2110941.2475150623, 3035636.2879365403}},
    {F3R_BEAM_FIXED_PINNED,
     12,
     6,
     {8.857734647725488e-06, 8.085455347661422e-06},
     {4201270.473723323, 5725061.573154566}},
    {F3R_BEAM_FIXED_PINNED,
     20,
     6,
     {9.524612737370827e-07, 9.033508123654714e-07},
     {30181068.442102727, 36622487.05245803}},
};

TEST(BeamBasis, DropsShapesWhoseResidualIsBelowTheTolerance) {
  for (const Trap& t : kTrap) {
    f3r_beam_basis b;
    const int asked = (t.set & 1) + (t.set >> 1 & 1) + (t.set >> 2 & 1);
    if (t.r + asked > F3R_MAX_MODES) {  // r = 20: no room, whatever the drop test would say
      EXPECT_EQ(f3r_beam_basis_build(t.end, t.r, t.set, &b), -1);
      continue;
    }
    ASSERT_EQ(f3r_beam_basis_build(t.end, t.r, t.set, &b), 0);
    int requested = 0, kept = 0;
    for (unsigned bit = 1; bit <= 4; bit <<= 1) {
      if (!(t.set & bit)) continue;
      const double ratio = t.ratio[requested++];
      if (ratio < F3R_SHAPE_DROP_RATIO) continue;
      ASSERT_LT(kept, b.shapes);
      EXPECT_EQ(b.shape_kind[kept], bit);
      EXPECT_NEAR(b.residual_ratio[kept], ratio, 1e-9 * ratio) << "r " << t.r << " shape " << bit;
      ++kept;
    }
    EXPECT_EQ(b.shapes, kept) << "end " << t.end << " r " << t.r << " set " << t.set;
    if (kept == requested)  // the reference's eigenvalues are those of the undropped set
      for (int m = 0; m < kept; ++m) {
        std::printf("end %d r %d set %u: lambda_%d relative error %.1e (ratio %.1e)\n", t.end, t.r,
                    t.set, m + 1, std::fabs(b.stiffness[t.r + m] / t.lambda[m] - 1), MinRatio(b));
        EXPECT_NEAR(b.stiffness[t.r + m] / t.lambda[m], 1.0, 1e-12);
      }
  }
}

// Clamped-free beam with a tip mass mu (in beam masses): exact lambda = beta^4 from
//   1 + cos b cosh b + mu b (cos b sinh b - sin b cosh b) = 0,
// divided by cosh b so that it stays bounded, by bisection in long double.
long double TipMassRoot(long double mu, long double lo, long double hi) {
  auto f = [mu](long double b) {
    return 1 / coshl(b) + cosl(b) + mu * b * (cosl(b) * tanhl(b) - sinl(b));
  };
  long double flo = f(lo);
  EXPECT_LT(flo * f(hi), 0) << "no bracket";
  for (int it = 0; it < 200; ++it) {
    const long double mid = 0.5L * (lo + hi), fm = f(mid);
    if ((fm < 0) == (flo < 0)) {
      lo = mid;
      flo = fm;
    } else {
      hi = mid;
    }
  }
  const long double b = 0.5L * (lo + hi);
  return b * b * b * b;
}

// The lowest Ritz value of (K, M + mu phi(1) phi(1)^T) on the basis, as 1 / the largest
// eigenvalue of K^-1/2 M K^-1/2 (K is diagonal) in long double: a Cholesky reduction of M would
// carry an error of eps times the largest eigenvalue (1e5 here) into the smallest.
double TipMassRitz(int r, unsigned set, double mu) {
  f3r_beam_basis b;
  EXPECT_EQ(f3r_beam_basis_build(F3R_BEAM_FIXED_FREE, r, set, &b), 0);
  using Matrix = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  const int n = b.count;
  Matrix B(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const long double m = (i == j ? 1.0L : 0.0L) + mu * (long double)b.tip[i] * b.tip[j];
      B(i, j) = m / sqrtl((long double)b.stiffness[i] * b.stiffness[j]);
    }
  Eigen::SelfAdjointEigenSolver<Matrix> es(B);
  return static_cast<double>(1.0L / es.eigenvalues()[n - 1]);
}

TEST(BeamBasis, TipMassFrequencyConvergesFasterWithTheCorrection) {
  const double exact = static_cast<double>(TipMassRoot(1.0L, 1.0L, 1.5L));
  EXPECT_NEAR(exact, 2.4251766284947336, 1e-14);  // reference: proxy_tipmass["1.0"]["exact"][0]
  // reference: proxy_tipmass["1.0"]["ritz"][...][0], 50 digits
  const struct {
    int r;
    unsigned set;
    double ritz;
  } rows[] = {
      {1, 0, 2.472472673665238},   // plain r=1
      {2, 0, 2.4324728855128117},  // plain r=2
      {3, 0, 2.4274638489212075},  // plain r=3
      {4, 0, 2.4261626123789792},  // plain r=4
      {5, 0, 2.425686745673123},   // plain r=5
      {6, 0, 2.4254735509606586},  // plain r=6
      {7, 0, 2.425364275138546},   // plain r=7
      {8, 0, 2.4253026289062216},  // plain r=8
      {1, 1, 2.425176755702142},   // r=1+{tip}
      {1, 3, 2.425176644688216},   // r=1+{tip,uniform}
      {1, 7, 2.425176629917444},   // r=1+{tip,uniform,linear}
      {2, 1, 2.425176628939677},   // r=2+{tip}
      {2, 3, 2.425176628625318},   // r=2+{tip,uniform}
      {2, 7, 2.4251766285242358},  // r=2+{tip,uniform,linear}
      {3, 1, 2.4251766285045213},  // r=3+{tip}
      {3, 3, 2.425176628499127},   // r=3+{tip,uniform}
      {3, 7, 2.4251766284963687},  // r=3+{tip,uniform,linear}
  };
  std::printf("clamped-free beam, tip mass = beam mass: lambda_1 = %.15g\n", exact);
  std::printf("  r  shapes  unknowns  relative error  (reference)\n");
  double err[2][4][8] = {};
  for (const auto& row : rows) {
    const double ritz = TipMassRitz(row.r, row.set, 1.0);
    const double rel = ritz / exact - 1, ref = row.ritz / exact - 1;
    std::printf("  %d  %u       %d         %.2e        (%.2e)\n", row.r, row.set,
                row.r + (row.set & 1) + (row.set >> 1 & 1) + (row.set >> 2 & 1), rel, ref);
    EXPECT_GT(rel, -1e-14) << "a Ritz value lies above the exact one";
    EXPECT_NEAR(ritz, row.ritz, 1e-13 * exact) << "r " << row.r << " set " << row.set;
    err[row.set ? 1 : 0][row.set == 3   ? 1
                         : row.set == 7 ? 2
                         : row.set == 1 ? 3
                                        : 0][row.r - 1] = rel;
  }
  const double plain8 = err[0][0][7], tip_uniform1 = err[1][1][0];
  EXPECT_LT(tip_uniform1, 1e-8);  // reference 6.7e-9
  EXPECT_GT(plain8, 5e-5);        // reference 5.2e-5
  EXPECT_LT(tip_uniform1 * 1000, plain8) << "r = 1 + {tip, uniform} beats the paper's r = 8";
}

TEST(BeamBasis, RejectsBadArguments) {
  f3r_beam_basis b;
  for (auto end : kEnds) {
    EXPECT_EQ(f3r_beam_basis_build(end, 0, 0, &b), -1);
    EXPECT_EQ(f3r_beam_basis_build(end, -1, kUniform, &b), -1);
    EXPECT_EQ(f3r_beam_basis_build(end, F3R_MAX_MODES + 1, 0, &b), -1);
    EXPECT_EQ(f3r_beam_basis_build(end, F3R_MAX_MODES, kUniform, &b), -1);
    EXPECT_EQ(f3r_beam_basis_build(end, F3R_MAX_MODES - 1, kUniform | kLinear, &b), -1);
    EXPECT_EQ(f3r_beam_basis_build(end, F3R_MAX_MODES - 1, kUniform, &b), 0);
    EXPECT_EQ(f3r_beam_basis_build(end, F3R_MAX_MODES, 0, &b), 0);
    EXPECT_EQ(f3r_beam_basis_build(end, 3, 8, &b), -1);  // no such shape
    EXPECT_EQ(f3r_beam_basis_build(end, 3, kUniform, nullptr), -1);
  }
  EXPECT_EQ(f3r_beam_basis_build(F3R_BEAM_FIXED_PINNED, 3, kTip, &b), -1);
  EXPECT_EQ(f3r_beam_basis_build(F3R_BEAM_FIXED_PINNED, 3, kTip | kUniform, &b), -1);
  EXPECT_EQ(
      f3r_beam_basis_build(F3R_BEAM_FIXED_FREE, F3R_MAX_MODES - 2, kTip | kUniform | kLinear, &b),
      -1);
  EXPECT_EQ(f3r_beam_basis_build(static_cast<f3r_beam_end>(0), 3, 0, &b), -1);
  EXPECT_EQ(f3r_beam_basis_build_mixed(3, NAN, &b), -1);
  EXPECT_EQ(f3r_beam_basis_build_mixed(3, INFINITY, &b), -1);
  EXPECT_EQ(f3r_beam_basis_build_mixed(F3R_MAX_MODES, -2.0, &b), -1);
  EXPECT_EQ(f3r_beam_basis_build_mixed(F3R_MAX_MODES - 1, -2.0, &b), 0);
  EXPECT_EQ(f3r_beam_basis_build_mixed(0, -2.0, &b), -1);
}

// The mixed correction (f3r_beam_basis_build_mixed): one function where the pair has two, built
// here independently in 192 bits from the shapes' exact polynomials: s = s_tip + mix s_uniform,
// its mass projections on the exact modes removed, normalised in mass, signed by its tip. The
// stored function must be that one, orthonormal to the modes with its stiffness on the diagonal,
// with its constants those of quadrature.
TEST(BeamBasis, MixedCorrectionIsOneFunctionOfBothLoads) {
  const int panels = 80, points = 10;
  double x[points], w[points];
  ASSERT_EQ(f3r_gauss_legendre(points, x, w), 0);
  double worst = 0.0;
  for (int r = 1; r <= 5; ++r)
    for (double mix : {-1.94, 0.5, -10.0}) {
      f3r_beam_basis b;
      ASSERT_EQ(f3r_beam_basis_build_mixed(r, mix, &b), 0);
      ASSERT_EQ(b.count, r + 1);
      ASSERT_EQ(b.corrections, 1);
      ASSERT_EQ(b.shapes, 2);
      EXPECT_EQ(b.mixed, 1);
      EXPECT_EQ(b.mix, mix);
      // the residual t = s - sum c_j psi_j, c_j = int s psi_j, on the exact modes
      std::vector<Mp> c(r, Mp(0.0));
      auto at = [&](const Mp& xi, Mp* psi_out) {
        Mp st, su, dd;
        Shape(F3R_BEAM_FIXED_FREE, kTip, xi, &st, &dd);
        Shape(F3R_BEAM_FIXED_FREE, kUniform, xi, &su, &dd);
        for (int j = 0; j < r; ++j)
          PrintedMode(F3R_BEAM_FIXED_FREE, b.alpha[j], xi, &psi_out[j], &dd);
        return st + Mp(mix) * su;
      };
      std::vector<Mp> psi(r, Mp(0.0));
      for (int p = 0; p < panels; ++p)
        for (int q = 0; q < points; ++q) {
          const Mp xi = (Mp(p) + Mp(x[q])) / Mp(panels), wq = Mp(w[q]) / Mp(panels);
          const Mp s = at(xi, psi.data());
          for (int j = 0; j < r; ++j) c[j] = c[j] + wq * s * psi[j];
        }
      auto residual = [&](const Mp& xi) {
        Mp t = at(xi, psi.data());
        for (int j = 0; j < r; ++j) t = t - c[j] * psi[j];
        return t;
      };
      Mp norm(0.0);
      for (int p = 0; p < panels; ++p)
        for (int q = 0; q < points; ++q) {
          const Mp xi = (Mp(p) + Mp(x[q])) / Mp(panels), wq = Mp(w[q]) / Mp(panels);
          const Mp t = residual(xi);
          norm = norm + wq * t * t;
        }
      const double scale = static_cast<double>((Mp(1.0) / Fn(mpfr_sqrt, norm)).ld());
      const double sign = residual(Mp(1.0)).ld() < 0 ? -1.0 : 1.0;
      for (double xi : {0.1, 0.37, 0.5, 0.81, 1.0}) {
        double phi;
        f3r_beam_basis_eval(&b, r, xi, &phi, nullptr, nullptr);
        const double expected = sign * scale * static_cast<double>(residual(Mp(xi)).ld());
        worst = std::max(worst, std::fabs(phi - expected));
        // the cancellation in s - sum c psi: as the pair's functions (OrthonormalWith...)
        EXPECT_NEAR(phi, expected, r <= 3 ? 3e-12 : 2e-11)
            << "r " << r << " mix " << mix << " xi " << xi;
      }
      EXPECT_GT(b.tip[r], 0.0);
      const Orthogonality o = Check(b), e = CheckExact(b);
      EXPECT_LT(o.mass, 1e-12) << "r " << r << " mix " << mix;
      EXPECT_LT(o.bending, 1e-12) << "r " << r << " mix " << mix;
      EXPECT_LT(e.mass, 1e-12) << "r " << r << " mix " << mix;
      EXPECT_LT(e.bending, 1e-12) << "r " << r << " mix " << mix;
      const Quadrature q = Integrate(b);
      double tip;
      f3r_beam_basis_eval(&b, r, 1.0, &tip, nullptr, nullptr);
      EXPECT_NEAR(q.mean[r], b.mean[r], 1e-13);
      EXPECT_NEAR(q.first_moment[r], b.first_moment[r], 1e-13);
      EXPECT_NEAR(tip, b.tip[r], 1e-13);
      // the first r functions are the paper's modes, as in the pair's basis
      f3r_beam_basis pair;
      ASSERT_EQ(f3r_beam_basis_build(F3R_BEAM_FIXED_FREE, r, kTip | kUniform, &pair), 0);
      for (int j = 0; j < r; ++j) EXPECT_EQ(b.alpha[j], pair.alpha[j]);
    }
  std::printf("mixed correction against its 192-bit construction: worst %.1e\n", worst);
}

}  // namespace

// The CSV's number formatting (src/core/base/csv_number.c) against snprintf's "%.*g": the same bytes
// for every double and precision tried, the fast path's hard cases (rounding ties, powers of ten
// and their neighbours, values outside its exact powers) included.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "flex3rpr/csv_number.h"

namespace {

const int kPrecisions[] = {1, 3, 10, 15, 17};

// The number of mismatches over xs at every precision; the first few are reported.
template <typename Values>
int Mismatches(const Values& xs) {
  int bad = 0;
  for (double x : xs)
    for (int p : kPrecisions) {
      char fast[F3R_FORMAT_G_SIZE], slow[64];
      const int n = f3r_format_g(fast, x, p);
      std::snprintf(slow, sizeof slow, "%.*g", p, x);
      if (std::strcmp(fast, slow) != 0 || n != static_cast<int>(std::strlen(slow))) {
        if (++bad <= 5)
          ADD_FAILURE() << "x = " << std::hexfloat << x << ", precision " << p << ": \"" << fast
                        << "\" against printf's \"" << slow << "\"";
      }
    }
  return bad;
}

TEST(CsvNumber, SpecialValuesAsPrintf) {
  const double xs[] = {
      0.0,      -0.0, INFINITY, -INFINITY, NAN,  DBL_MAX, -DBL_MAX,  DBL_MIN,
      4.9e-324, 1.0,  -1.0,     0.1,       1e-5, 1e-4,    9.9999e-5, 123456789012345678.0,
      1e15,     1e17};
  EXPECT_EQ(Mismatches(xs), 0);
}

// Exact ties of the decimal rounding ((n + 1/2) 10^j, representable for small j) and the values a
// few ulps either side of powers of ten and of ties: where a wrong rounding would show.
TEST(CsvNumber, TiesAndPowersOfTenAsPrintf) {
  std::vector<double> xs;
  for (int n = 0; n < 2000; ++n)
    for (int j = -3; j <= 16; ++j) xs.push_back((n + 0.5) * std::pow(2.0, -j) * std::pow(10.0, j));
  for (double base : {0.5, 1.5, 2.5, 0.125, 0.375, 100000000000000.5, 123456789012345.5, 9.5,
                      99999999999999.5, 999999999999999.5})
    xs.push_back(base);
  for (int k = -30; k <= 30; ++k) {
    double x = std::pow(10.0, k);
    for (int u = 0; u < 4; ++u) x = std::nextafter(x, 0.0);
    for (int u = 0; u < 9; ++u, x = std::nextafter(x, INFINITY)) xs.push_back(x);
    xs.push_back(9.5 * std::pow(10.0, k));
    xs.push_back(9.9999999999999995 * std::pow(10.0, k));
  }
  EXPECT_EQ(Mismatches(xs), 0);
}

// Random bit patterns (every exponent, subnormals, NaNs) and values spread like a simulation's:
// log-uniform over 1e-20 .. 1e6, either sign.
TEST(CsvNumber, RandomDoublesAsPrintf) {
  std::mt19937_64 rng(20261126);
  std::vector<double> xs;
  for (int k = 0; k < 200000; ++k) {
    const std::uint64_t bits = rng();
    double x;
    std::memcpy(&x, &bits, sizeof x);
    xs.push_back(x);
  }
  std::uniform_real_distribution<double> exponent(-20.0, 6.0);
  for (int k = 0; k < 400000; ++k)
    xs.push_back((k % 2 ? -1.0 : 1.0) * std::pow(10.0, exponent(rng)));
  EXPECT_EQ(Mismatches(xs), 0);
}

}  // namespace

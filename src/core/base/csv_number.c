/* "%.*g" without printf's multiple-precision arithmetic. glibc formats a double exactly, with
 * big-number arithmetic: 177 ns a number in the CLI, where a run at 0.1 ms outputs writes 265 000
 * of them. This file rounds exactly too, in 128-bit integers: x = m 2^q (m < 2^53), and the
 * `precision` digits are round(x 10^k) for the k that puts them before the point; x 10^k =
 * m 5^k 2^(q+k) for k >= 0 and m 2^(q+k) / 5^-k for k < 0, an integer and a remainder that decide
 * the rounding (ties to even, as glibc rounds an exact tie in the default rounding mode). The
 * digits are laid out by %g's rules (C11 7.21.6.1): exponent X of the rounded value; %e style
 * when X < -4 or X >= precision, else %f style; trailing zeros and a bare point removed. What
 * does not fit 128 bits (at 15 digits, |x| below 1e-13 or above 1e41), subnormals, zeros and
 * non-finite values go to snprintf (test_csv_number compares the two). 30 ns a number. */
#include "flex3rpr/csv_number.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#ifndef __SIZEOF_INT128__
#error "csv_number.c needs unsigned __int128 (GCC or Clang on a 64-bit target)"
#endif
__extension__ typedef unsigned __int128 u128;

static int format_slow(char* buf, double x, int precision) {
  return snprintf(buf, F3R_FORMAT_G_SIZE, "%.*g", precision, x);
}

/* 5^0 .. 5^27 (5^27 < 2^63) and 10^0 .. 10^18. */
static const uint64_t kPower5[] = {1,
                                   5,
                                   25,
                                   125,
                                   625,
                                   3125,
                                   15625,
                                   78125,
                                   390625,
                                   1953125,
                                   9765625,
                                   48828125,
                                   244140625,
                                   1220703125,
                                   6103515625,
                                   30517578125,
                                   152587890625,
                                   762939453125,
                                   3814697265625,
                                   19073486328125,
                                   95367431640625,
                                   476837158203125,
                                   2384185791015625,
                                   11920928955078125,
                                   59604644775390625,
                                   298023223876953125,
                                   1490116119384765625,
                                   7450580596923828125u};
static const uint64_t kPower10[] = {1,
                                    10,
                                    100,
                                    1000,
                                    10000,
                                    100000,
                                    1000000,
                                    10000000,
                                    100000000,
                                    1000000000,
                                    10000000000,
                                    100000000000,
                                    1000000000000,
                                    10000000000000,
                                    100000000000000,
                                    1000000000000000,
                                    10000000000000000,
                                    100000000000000000,
                                    1000000000000000000};

/* round(m 2^q 10^k) into *n, ties to even; 0 when it does not fit the arithmetic. */
static int scaled_round(uint64_t m, int q, int k, uint64_t* n) {
  const int s = q + k;    /* the power of two left after 10^k = 5^k 2^k */
  u128 whole, rem, half2; /* rounding: compare 2 rem with half2 (the divisor) */
  if (k >= 0) {
    if (k > 27) return 0; /* 5^27 < 2^63: m 5^k < 2^116 */
    const u128 p = (u128)m * kPower5[k];
    if (s >= 0) { /* an integer: no rounding */
      if (s > 10 || p >> (62 - s)) return 0;
      *n = (uint64_t)(p << s);
      return 1;
    }
    if (-s > 120) return 0;
    whole = p >> -s;
    rem = p & (((u128)1 << -s) - 1);
    half2 = (u128)1 << -s;
  } else {
    if (-k > 27) return 0;
    const u128 five = kPower5[-k];
    if (s >= 0) {
      if (s > 60) return 0; /* m 2^s < 2^113 */
      const u128 num = (u128)m << s;
      whole = num / five, rem = num % five, half2 = five;
    } else {
      if (-s > 60) return 0; /* 5^-k 2^-s < 2^124 */
      const u128 den = five << -s;
      whole = m / den, rem = m % den, half2 = den;
    }
  }
  if (whole >> 63) return 0;
  const u128 twice = rem * 2;
  *n = (uint64_t)whole + (twice > half2 || (twice == half2 && (whole & 1)));
  return 1;
}

/* The `count` decimal digits of v, leading zeros included, into dst, two at a time. */
static void put_digits(char* dst, int count, uint32_t v) {
  static const char kPairs[] =
      "00010203040506070809101112131415161718192021222324252627282930313233343536373839404142434445"
      "46474849"
      "50515253545556575859606162636465666768697071727374757677787980818283848586878889909192939495"
      "96979899";
  for (; count >= 2; count -= 2, v /= 100) memcpy(dst + count - 2, kPairs + 2 * (v % 100), 2);
  if (count) dst[0] = (char)('0' + v % 10);
}

/* The `precision` significant digits of x (finite, normal, not zero; its sign ignored) into
 * digits, and their decimal exponent X in *exponent; 0 when the arithmetic cannot hold them. */
static int round_digits(double x, int precision, char* digits, int* exponent) {
  uint64_t bits;
  memcpy(&bits, &x, sizeof bits);
  const int biased = (int)(bits >> 52 & 0x7ff);
  if (biased == 0 || biased == 0x7ff) return 0; /* zero, subnormal, inf, nan */
  const uint64_t m = (bits & ((UINT64_C(1) << 52) - 1)) | UINT64_C(1) << 52;
  const int q = biased - 1075; /* x = m 2^q, x in [2^(q+52), 2^(q+53)) */
  /* floor(log10 x) or one less: floor((q + 52) log10 2) as (n 78913) >> 18 (an arithmetic
   * shift: GCC's and Clang's on signed ints; for negative n it may come out one more, and the
   * next lines correct that too) */
  int e = ((q + 52) * 78913) >> 18;
  const uint64_t lo = kPower10[precision - 1], hi = kPower10[precision];
  uint64_t n;
  if (!scaled_round(m, q, precision - 1 - e, &n)) return 0;
  if (n > hi || n < lo) { /* e one off: x 10^k has precision + 1 digits, or precision - 1 */
    e += n > hi ? 1 : -1;
    if (!scaled_round(m, q, precision - 1 - e, &n)) return 0;
  }
  if (n == hi) n = lo, ++e; /* rounded up to the next power of ten */
  if (n < lo || n >= hi) return 0;
  if (precision > 8) { /* two independent 32-bit chains of divisions, not one of 64 */
    put_digits(digits + precision - 8, 8, (uint32_t)(n % 100000000));
    put_digits(digits, precision - 8, (uint32_t)(n / 100000000));
  } else {
    put_digits(digits, precision, (uint32_t)n);
  }
  *exponent = e;
  return 1;
}

int f3r_format_g(char* buf, double x, int precision) {
  if (precision == 0) precision = 1; /* as %g: a precision of zero is taken as one */
  if (precision < 0 || precision > 17) return format_slow(buf, x, precision);
  char digits[17];
  int X;
  if (!round_digits(x, precision, digits, &X)) return format_slow(buf, x, precision);
  int kept = precision; /* digits left once the trailing zeros go */
  while (kept > 1 && digits[kept - 1] == '0') --kept;
  char* out = buf;
  if (x < 0.0) *out++ = '-';
  if (X < -4 || X >= precision) { /* %e style */
    *out++ = digits[0];
    if (kept > 1) {
      *out++ = '.';
      memcpy(out, digits + 1, (size_t)(kept - 1));
      out += kept - 1;
    }
    *out++ = 'e';
    *out++ = X < 0 ? '-' : '+';
    const int a = X < 0 ? -X : X;
    if (a >= 100) *out++ = (char)('0' + a / 100);
    *out++ = (char)('0' + a / 10 % 10);
    *out++ = (char)('0' + a % 10);
  } else if (X >= 0) { /* %f style, X + 1 digits before the point */
    memcpy(out, digits, (size_t)X + 1);
    out += X + 1;
    if (kept > X + 1) {
      *out++ = '.';
      memcpy(out, digits + X + 1, (size_t)(kept - X - 1));
      out += kept - X - 1;
    }
  } else { /* %f style, 0.000ddd */
    *out++ = '0';
    *out++ = '.';
    for (int z = 0; z < -X - 1; ++z) *out++ = '0';
    memcpy(out, digits, (size_t)kept);
    out += kept;
  }
  *out = '\0';
  return (int)(out - buf);
}

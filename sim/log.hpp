// Natural logarithm, the same bits on every x86-64 machine, for the toss's random draws.
//
// Why not libm: glibc's log picks an implementation at run time (an FMA variant on CPUs that have
// FMA), and the variants round differently for about one argument in 10^4 (measured: 2 200 of
// 2*10^7 uniform arguments, glibc 2.36 with GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA). Every
// toss draws its throw through Box-Muller (sim/models/toss_random.hpp), so a toss's initial state,
// and with it its result, could depend on the CPU of the worker that tossed it. Here x = 2^k m
// with m in [1/sqrt 2, sqrt 2] (bit operations, exact), f = m - 1 (exact, Sterbenz),
// s = f / (2 + f), and log m = 2 atanh s = f - s (f - R) with R = sum_{n>=1} 2 s^(2n) / (2n + 1)
// (|s| <= 0.1716, eleven terms leave < 1e-19 out); then k ln 2 in two parts (the high part has
// 41 bits, so k times it is exact), added as below. Only IEEE additions, multiplications and one division, and
// the build forbids FMA contraction, so the result is a fixed function of x. Accuracy, checked
// against long double by tests/test_log.cpp: within 1 ulp. Zero, negative, subnormal, infinite
// and NaN arguments go to libm (a uniform draw in (0, 1) with 53 bits is never one of them).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

namespace dicesim {

inline double log_fixed(double x) {
  if (!(x >= 0x1p-1022 && x <= 0x1.fffffffffffffp+1023)) return std::log(x);
  const std::uint64_t bits = std::bit_cast<std::uint64_t>(x);
  int k = static_cast<int>(bits >> 52) - 1023;
  double m = std::bit_cast<double>((bits & 0x000fffffffffffffULL) | 0x3ff0000000000000ULL);  // [1, 2)
  if (m > 0x1.6a09e667f3bcdp+0) {  // sqrt 2
    m *= 0.5;
    ++k;
  }
  const double f = m - 1.0;
  const double s = f / (2.0 + f);
  const double z = s * s, z2 = z * z, z4 = z2 * z2, z8 = z4 * z4;
  // R = z (c1 + z c2 + ... + z^10 c11), c_n = 2 / (2n + 1), in Estrin's scheme (short chains).
  const double p01 = 2.0 / 3.0 + z * (2.0 / 5.0), p23 = 2.0 / 7.0 + z * (2.0 / 9.0);
  const double p45 = 2.0 / 11.0 + z * (2.0 / 13.0), p67 = 2.0 / 15.0 + z * (2.0 / 17.0);
  const double p89 = 2.0 / 19.0 + z * (2.0 / 21.0), p10 = 2.0 / 23.0;
  const double R = z * ((p01 + z2 * p23) + z4 * (p45 + z2 * p67) + z8 * (p89 + z2 * p10));
  constexpr double kLn2Hi = 0x1.62e42fefa2000p-1;  // ln 2 to 41 bits
  constexpr double kLn2Lo = 0x1.9ef35793c7673p-41;  // the rest
  const double dk = static_cast<double>(k);
  // log x = k ln2_hi + f + (k ln2_lo - s (f - R)): the first sum with its exact rounding error
  // (Knuth's two-sum), so only the last addition rounds at the result's scale (where log m and
  // the result share a binade, two roundings there made 1.13 ulp).
  const double hi = dk * kLn2Hi;  // exact
  const double a = hi + f;
  const double b = a - hi;
  const double err = (hi - (a - b)) + (f - b);
  return a + (err + (dk * kLn2Lo - s * (f - R)));
}

}  // namespace dicesim

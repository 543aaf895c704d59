// Sine and cosine together, the same bits on every x86-64 machine, inlined for the toss's hot path.
//
// Why not libm: glibc's sin/cos/sincos pick an implementation at run time (an FMA variant on CPUs
// that have FMA), so the last bit of a result, and through it a chaotic toss's face, could depend
// on the machine; and a call costs ~20-35 ns where this costs a fraction. Here the argument is
// reduced by pi/2 (Cody-Waite: pi/2 split in three, the first two parts 33 bits wide so that
// k * part is exact for |k| < 2^20) and sine and cosine of the remainder r, |r| <= pi/4, come
// from their Taylor polynomials to r^17 and r^18 (the omitted terms are below 1e-18 relative).
// Only IEEE additions and multiplications are used, and the build forbids FMA contraction
// (-ffp-contract=off), so the result is a fixed function of x. Accuracy, checked against long
// double over 10^6 angles by tests/test_sincos.cpp: within 1 ulp of the exact value for
// |x| <= 10^6 (beyond, and for inf/NaN, it falls back to libm: no toss comes near).
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace dicesim {

struct SinCos {
  double sin, cos;
};

namespace sincos_detail {

inline constexpr double fact(int n) { return n <= 1 ? 1.0 : n * fact(n - 1); }  // exact up to 18!

// sin and cos of r + rr for |r| <= pi/4 (a little beyond is fine), |rr| <= ulp(r): the remainder
// carried in two parts. Estrin's scheme (powers z, z^2, z^4 of z = r^2) keeps the dependency chain
// short; the Taylor terms up to r^17 (sine) and r^18 (cosine) leave < 1e-18 relative out.
inline SinCos kernel(double r, double rr) {
  const double z = r * r, z2 = z * z, z4 = z2 * z2;
  const double ps = ((-1.0 / fact(3) + z * (1.0 / fact(5))) + z2 * (-1.0 / fact(7) + z * (1.0 / fact(9)))) +
                    z4 * ((-1.0 / fact(11) + z * (1.0 / fact(13))) + z2 * (-1.0 / fact(15) + z * (1.0 / fact(17))));
  const double pc = ((1.0 / fact(4) + z * (-1.0 / fact(6))) + z2 * (1.0 / fact(8) + z * (-1.0 / fact(10)))) +
                    z4 * ((1.0 / fact(12) + z * (-1.0 / fact(14))) + z2 * (1.0 / fact(16) + z * (-1.0 / fact(18))));
  // cos r = 1 - z/2 + z^2 pc: w = 1 - z/2 rounded, and (1 - w) - z/2 its exact rounding error
  // (z/2 <= 0.31 < 1), so the large cancellation-free part keeps full precision. The low part rr
  // enters to first order: sin(r + rr) = sin r + rr cos r, cos(r + rr) = cos r - rr sin r.
  const double hz = 0.5 * z;
  const double w = 1.0 - hz;
  const double s = r + ((r * z) * ps + rr * w);
  const double c = w + (((1.0 - w) - hz) + ((z * z) * pc - r * rr));
  return {s, c};
}

// Quadrant k (mod 4): (sin, cos)(r + k pi/2) from (s, c) = (sin r, cos r), without branches (the
// quadrant of a random angle is unpredictable).
inline SinCos rotate_quadrant(const SinCos& sc, std::int64_t k) {
  const std::uint64_t q = static_cast<std::uint64_t>(k);
  const std::uint64_t swap = 0 - (q & 1);  // odd quadrant: sin <-> cos
  const std::uint64_t sb = std::bit_cast<std::uint64_t>(sc.sin), cb = std::bit_cast<std::uint64_t>(sc.cos);
  std::uint64_t s = (sb & ~swap) | (cb & swap), c = (cb & ~swap) | (sb & swap);
  s ^= ((q >> 1) & 1) << 63;        // quadrants 2, 3: sin negative
  c ^= (((q + 1) >> 1) & 1) << 63;  // quadrants 1, 2: cos negative
  return {std::bit_cast<double>(s), std::bit_cast<double>(c)};
}

// Round to the nearest integer (ties to even) for |x| < 2^51, without SSE4.1's roundsd and
// without a libm call: adding and subtracting 1.5 * 2^52 leaves no fraction bits.
inline double round_nearest(double x) {
  constexpr double kShift = 0x1.8p52;
  return (x + kShift) - kShift;
}

}  // namespace sincos_detail

// sin x and cos x (see the file comment for accuracy and determinism).
inline SinCos sincos(double x) {
  using namespace sincos_detail;
  if (!(std::abs(x) <= 1e6)) return {std::sin(x), std::cos(x)};  // |k| would pass 2^20; inf, NaN
  constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
  constexpr double kPio2Hi = 0x1.921fb544p+0;          // 33 bits of pi/2
  constexpr double kPio2Mid = 0x1.0b4611a6p-34;        // the next 33 bits
  constexpr double kPio2Lo = 0x1.3198a2e037073p-69;    // the rest, rounded
  const double k = round_nearest(x * kTwoOverPi);
  // x - k pi/2 as r + rr: r1 is exact (k * kPio2Hi has <= 53 bits and is within a factor two of
  // x), r1 - k * kPio2Mid is rounded and its error recovered exactly (Knuth's two-sum).
  const double r1 = x - k * kPio2Hi, t = -(k * kPio2Mid);
  const double r2 = r1 + t;
  const double b = r2 - r1;
  const double lo = ((r1 - (r2 - b)) + (t - b)) - k * kPio2Lo;
  const double r = r2 + lo;
  return rotate_quadrant(kernel(r, (r2 - r) + lo), static_cast<std::int64_t>(k));
}

// sin(2 pi u) and cos(2 pi u), e.g. for a uniform angle drawn as a fraction u of a turn. The
// reduction in turns is exact (4u - k needs no rounding), so this is as accurate as sincos.
inline SinCos sincos_turns(double u) {
  using namespace sincos_detail;
  if (!(std::abs(u) <= 1e6)) return {std::sin(2.0 * 3.14159265358979323846 * u), std::cos(2.0 * 3.14159265358979323846 * u)};
  constexpr double kPio2 = 0x1.921fb54442d18p+0;
  const double u4 = 4.0 * u;
  const double k = round_nearest(u4);
  return rotate_quadrant(kernel((u4 - k) * kPio2, 0.0), static_cast<std::int64_t>(k));
}

#if defined(__SSE2__)
namespace sincos_detail {
#define DICESIM_PAIR(x) (x), (x)
// sincos2's constants, each twice (one packed pair): the reduction's shift, 2/pi, pi/2 in three
// parts, the sign bit, 1/2, 1, then the sine's and the cosine's Taylor coefficients.
alignas(16) inline constexpr double kSincos2Constants[48] = {
    DICESIM_PAIR(0x1.8p52),           DICESIM_PAIR(0x1.45f306dc9c883p-1), DICESIM_PAIR(0x1.921fb544p+0),
    DICESIM_PAIR(0x1.0b4611a6p-34),   DICESIM_PAIR(0x1.3198a2e037073p-69), DICESIM_PAIR(-0.0),
    DICESIM_PAIR(0.5),                DICESIM_PAIR(1.0),
    DICESIM_PAIR(-1.0 / fact(3)),     DICESIM_PAIR(1.0 / fact(5)),        DICESIM_PAIR(-1.0 / fact(7)),
    DICESIM_PAIR(1.0 / fact(9)),      DICESIM_PAIR(-1.0 / fact(11)),      DICESIM_PAIR(1.0 / fact(13)),
    DICESIM_PAIR(-1.0 / fact(15)),    DICESIM_PAIR(1.0 / fact(17)),
    DICESIM_PAIR(1.0 / fact(4)),      DICESIM_PAIR(-1.0 / fact(6)),       DICESIM_PAIR(1.0 / fact(8)),
    DICESIM_PAIR(-1.0 / fact(10)),    DICESIM_PAIR(1.0 / fact(12)),       DICESIM_PAIR(-1.0 / fact(14)),
    DICESIM_PAIR(1.0 / fact(16)),     DICESIM_PAIR(-1.0 / fact(18))};
#undef DICESIM_PAIR
}  // namespace sincos_detail
#endif

// Two angles at once: the same numbers as {sincos(x), sincos(y)}, bit for bit (each lane does the
// same IEEE operations in the same order), at about the cost of one with SSE2.
// (Forced inline: the torque-free rotation's hot path calls it, and GCC kept it out of line there.)
[[gnu::always_inline]] inline void sincos2(double x, double y, SinCos& sx, SinCos& sy) {
#if defined(__SSE2__)
  using namespace sincos_detail;
  if (!(std::abs(x) <= 1e6) || !(std::abs(y) <= 1e6)) {
    sx = sincos(x);
    sy = sincos(y);
    return;
  }
  const __m128d v = _mm_set_pd(y, x);
  // The constants as packed pairs loaded from a table whose address the compiler may not see
  // through (the empty asm): GCC 12 otherwise turns every `_mm_set1_pd(constant)` into a scalar
  // load and a broadcast, two instructions for one (~30 of this function's ~200).
  const double* kc = kSincos2Constants;
  asm("" : "+r"(kc));
  const auto c = [kc](int i) { return _mm_load_pd(kc + 2 * i); };
  const __m128d shift = c(0);
  const __m128d k = _mm_sub_pd(_mm_add_pd(_mm_mul_pd(v, c(1)), shift), shift);
  const __m128d r1 = _mm_sub_pd(v, _mm_mul_pd(k, c(2)));
  const __m128d t = _mm_xor_pd(_mm_mul_pd(k, c(3)), c(5));  // -(k mid)
  const __m128d r2 = _mm_add_pd(r1, t);
  const __m128d b = _mm_sub_pd(r2, r1);
  const __m128d lo = _mm_sub_pd(_mm_add_pd(_mm_sub_pd(r1, _mm_sub_pd(r2, b)), _mm_sub_pd(t, b)), _mm_mul_pd(k, c(4)));
  const __m128d r = _mm_add_pd(r2, lo);
  const __m128d rr = _mm_add_pd(_mm_sub_pd(r2, r), lo);
  // kernel(r, rr), lane by lane the same expression tree.
  const auto mul = [](__m128d a, __m128d b_) { return _mm_mul_pd(a, b_); };
  const auto add = [](__m128d a, __m128d b_) { return _mm_add_pd(a, b_); };
  const __m128d z = mul(r, r), z2 = mul(z, z), z4 = mul(z2, z2);
  const __m128d ps = add(add(add(c(8), mul(z, c(9))), mul(z2, add(c(10), mul(z, c(11))))),
                         mul(z4, add(add(c(12), mul(z, c(13))), mul(z2, add(c(14), mul(z, c(15)))))));
  const __m128d pc = add(add(add(c(16), mul(z, c(17))), mul(z2, add(c(18), mul(z, c(19))))),
                         mul(z4, add(add(c(20), mul(z, c(21))), mul(z2, add(c(22), mul(z, c(23)))))));
  const __m128d hz = mul(c(6), z);
  const __m128d w = _mm_sub_pd(c(7), hz);
  const __m128d s = add(r, add(mul(mul(r, z), ps), mul(rr, w)));
  const __m128d co = add(w, add(_mm_sub_pd(_mm_sub_pd(c(7), w), hz), _mm_sub_pd(mul(mul(z, z), pc), mul(r, rr))));
  // rotate_quadrant for both lanes, in the vector registers: the same bits. |k| < 2^20, so its 32-bit
  // truncation has the low bits of the 64-bit one, and each 64-bit lane gets its k in both halves.
  const __m128i ki = _mm_cvttpd_epi32(k);
  const __m128i kk = _mm_unpacklo_epi32(ki, ki);
  const __m128i high = _mm_set_epi32(INT32_MIN, 0, INT32_MIN, 0);                   // bit 63 of each lane
  const __m128d swap = _mm_castsi128_pd(_mm_srai_epi32(_mm_slli_epi32(kk, 31), 31));  // odd quadrant: all ones
  const __m128d sign_s = _mm_castsi128_pd(_mm_and_si128(_mm_slli_epi32(kk, 30), high));  // bit 1 of k
  const __m128d sign_c = _mm_castsi128_pd(_mm_and_si128(_mm_slli_epi32(_mm_add_epi32(kk, _mm_set1_epi32(1)), 30), high));
  const __m128d qs = _mm_xor_pd(_mm_or_pd(_mm_andnot_pd(swap, s), _mm_and_pd(swap, co)), sign_s);
  const __m128d qc = _mm_xor_pd(_mm_or_pd(_mm_andnot_pd(swap, co), _mm_and_pd(swap, s)), sign_c);
  sx = {_mm_cvtsd_f64(qs), _mm_cvtsd_f64(qc)};
  sy = {_mm_cvtsd_f64(_mm_unpackhi_pd(qs, qs)), _mm_cvtsd_f64(_mm_unpackhi_pd(qc, qc))};
#else
  sx = sincos(x);
  sy = sincos(y);
#endif
}

}  // namespace dicesim

// Tests for the hand-written logarithm (sim/log.hpp): accuracy against long double over the
// arguments a toss draws (uniform in (0, 1)) and far beyond, and pinned bits (the function is part
// of every toss's initial state, so a change to it is a change of the pinned counts).
#include "sim/log.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <unistd.h>
#include <string>

#include "sim/models/toss_random.hpp"

namespace dicesim {
namespace {

double ulps(double got, long double exact) {
  const double e = static_cast<double>(exact);
  const double a = std::abs(e);
  const double ulp = std::nextafter(a, std::numeric_limits<double>::infinity()) - a;
  return static_cast<double>(std::fabs(static_cast<long double>(got) - exact)) / ulp;
}

TEST(LogFixed, WithinOneUlpOfLongDouble) {
  std::mt19937_64 gen(3);
  double worst = 0.0;
  // Uniform draws as TossRandom makes them (53 bits, (0, 1)), then wide ranges of magnitude and
  // the neighbourhood of 1, where log is small and the relative error matters most.
  for (int i = 0; i < 300000; ++i) {
    const double u = (static_cast<double>(gen() >> 11) + 0.5) * 0x1.0p-53;
    worst = std::max(worst, ulps(log_fixed(u), std::log(static_cast<long double>(u))));
  }
  std::uniform_real_distribution<double> expo(-1000.0, 1000.0), near1(-1e-3, 1e-3);
  for (int i = 0; i < 100000; ++i) {
    const double x = std::exp2(expo(gen));
    worst = std::max(worst, ulps(log_fixed(x), std::log(static_cast<long double>(x))));
    const double y = 1.0 + near1(gen);
    if (y != 1.0) worst = std::max(worst, ulps(log_fixed(y), std::log(static_cast<long double>(y))));
  }
  // Measured 0.82 ulp (libm's own: 0.52).
  EXPECT_LT(worst, 1.0);
  EXPECT_GT(worst, 0.5);  // not correctly rounded: the test does measure something
  EXPECT_EQ(log_fixed(1.0), 0.0);
  EXPECT_EQ(log_fixed(2.0), static_cast<double>(std::log(2.0L)));
}

TEST(LogFixed, OutsideItsRangeItIsLibm) {
  EXPECT_TRUE(std::isnan(log_fixed(-1.0)));
  EXPECT_EQ(log_fixed(0.0), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(log_fixed(std::numeric_limits<double>::infinity()), std::numeric_limits<double>::infinity());
  EXPECT_EQ(log_fixed(0x1p-1074), std::log(0x1p-1074));
}

// The bits of 10^5 results, hashed: every toss's throw goes through this function, so a change to
// it must be a visible decision (the pinned counts of every fidelity may move with it).
TEST(LogFixed, BitsArePinned) {
  std::uint64_t h = 1469598103934665603ULL;
  for (std::uint64_t i = 1; i <= 100000; ++i) {
    const double u = (static_cast<double>(i * 0x9e3779b97f4a7c15ULL >> 11) + 0.5) * 0x1.0p-53;
    h = (h ^ std::bit_cast<std::uint64_t>(log_fixed(u))) * 1099511628211ULL;
  }
  EXPECT_EQ(h, 14573468511602971210ULL);
}

// What a toss draws: hashes of 2*10^5 tosses' first six normal draws through TossRandom, and of
// libm's log of the same uniforms (the control).
struct DrawHashes {
  std::uint64_t draws = 1469598103934665603ULL, libm = 1469598103934665603ULL;
};
DrawHashes draw_hashes() {
  DrawHashes h;
  for (std::uint64_t t = 0; t < 200000; ++t) {
    TossRandom normals(20261122, t), uniforms(20261122, t);
    for (int k = 0; k < 6; ++k) {
      h.draws = (h.draws ^ std::bit_cast<std::uint64_t>(normals.normal())) * 1099511628211ULL;
      h.libm = (h.libm ^ std::bit_cast<std::uint64_t>(std::log(uniforms.uniform()))) * 1099511628211ULL;
    }
  }
  return h;
}

// The same draws whichever variant of libm the CPU selects: this binary again, in a child whose
// glibc is told the CPU has no FMA/AVX2 (GLIBC_TUNABLES), must draw the same bits. The control:
// libm's own log of the same arguments does change there (~1e-4 of them), so the switch took
// effect and the comparison means something. (With std::log in TossRandom this test failed.)
TEST(LogFixed, SameDrawsWhicheverLibmVariantTheCpuSelects) {
  if (std::getenv("DICESIM_DRAW_HASHES_CHILD")) {  // the child: print and stop
    const DrawHashes h = draw_hashes();
    std::printf("draw-hashes %llu %llu\n", static_cast<unsigned long long>(h.draws), static_cast<unsigned long long>(h.libm));
    return;
  }
  if (!__builtin_cpu_supports("fma") || !__builtin_cpu_supports("avx2")) {
    if (std::getenv("CI") && std::string(std::getenv("CI")) == "true") FAIL() << "this CPU has no FMA/AVX2 variant to compare";
    GTEST_SKIP() << "no FMA/AVX2: glibc has only one variant here";
  }
  const DrawHashes here = draw_hashes();
  const std::string cmd = "DICESIM_DRAW_HASHES_CHILD=1 GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-FMA4,-AVX /proc/" +
                          std::to_string(::getpid()) + "/exe --gtest_filter=LogFixed.SameDrawsWhicheverLibmVariantTheCpuSelects";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  char line[512];
  unsigned long long draws = 0, libm = 0;
  bool found = false;
  while (std::fgets(line, sizeof line, p))
    if (std::sscanf(line, "draw-hashes %llu %llu", &draws, &libm) == 2) found = true;
  ASSERT_EQ(pclose(p), 0);
  ASSERT_TRUE(found) << cmd;
  EXPECT_NE(libm, here.libm) << "libm's log gave the same bits without FMA: the switch did not take effect";
  EXPECT_EQ(draws, here.draws) << "a toss's draws depend on the CPU";
}

}  // namespace
}  // namespace dicesim

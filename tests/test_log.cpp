// Tests for the hand-written logarithm (sim/log.hpp): accuracy against long double over the
// arguments a toss draws (uniform in (0, 1)) and far beyond, and pinned bits (the function is part
// of every toss's initial state, so a change to it is a change of the pinned counts).
#include "sim/log.hpp"

#include <gtest/gtest.h>

#include "ulps.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

namespace dicesim {
namespace {

using dicesim::testing::ulps;

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

}  // namespace
}  // namespace dicesim

// Wilson intervals and chi-square against values computed by hand / from tables.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "sim/study/statistics.hpp"

using namespace dicesim;

TEST(Wilson, MatchesClosedFormAtHalf) {
  // n = 100, x = 50: centre 0.5, half = z sqrt(0.25/100 + z^2/40000) / (1 + z^2/100).
  const double z = kZ95;
  const double half = z * std::sqrt(0.25 / 100 + z * z / 40000.0) / (1 + z * z / 100.0);
  const Interval ci = wilson_interval(50, 100);
  EXPECT_NEAR(ci.lo, 0.5 - half, 1e-15);
  EXPECT_NEAR(ci.hi, 0.5 + half, 1e-15);
}

TEST(Wilson, KnownValueSmallSample) {
  // A textbook case: 0 successes of 10 -> [0, 0.2775] (z = 1.96).
  const Interval ci = wilson_interval(0, 10);
  EXPECT_EQ(ci.lo, 0.0);
  EXPECT_NEAR(ci.hi, 0.27753, 5e-5);
  const Interval all = wilson_interval(10, 10);
  EXPECT_NEAR(all.lo, 1.0 - 0.27753, 5e-5);
  EXPECT_NEAR(all.hi, 1.0, 1e-15);
}

TEST(Wilson, HalfWidthShrinksAsOneOverRootN) {
  const double h1 = wilson_interval(1667, 10000).half_width();
  const double h2 = wilson_interval(166700, 1000000).half_width();
  EXPECT_NEAR(h1 / h2, 10.0, 0.05);
  // PHYSICS.md: about 535 000 tosses for h = 0.001 at p = 1/6 (z^2 = 3.841458820694124).
  EXPECT_NEAR(tosses_for_halfwidth(1.0 / 6.0, 0.001), 3.841458820694124 * 5.0 / 36.0 * 1e6, 1e-6);
}

TEST(Wilson, EmptySampleIsWholeRange) {
  const Interval ci = wilson_interval(0, 0);
  EXPECT_EQ(ci.lo, 0.0);
  EXPECT_EQ(ci.hi, 1.0);
}

TEST(ChiSquare, UniformCountsGiveZero) {
  const std::array<std::uint64_t, 6> c{100, 100, 100, 100, 100, 100};
  const ChiSquare r = chi2_uniform(c);
  EXPECT_EQ(r.statistic, 0.0);
  EXPECT_EQ(r.dof, 5);
  EXPECT_NEAR(r.p_value, 1.0, 1e-12);
}

TEST(ChiSquare, KnownStatisticAndPValue) {
  // Expected 100 each; statistic = (400 + 400 + 0 + 0 + 100 + 100)/100 = 10 on 5 dof;
  // P(chi2_5 > 10) = 0.07523524614651217 (tables).
  const std::array<std::uint64_t, 6> c{120, 80, 100, 100, 110, 90};
  const ChiSquare r = chi2_uniform(c);
  EXPECT_NEAR(r.statistic, 10.0, 1e-12);
  EXPECT_NEAR(r.p_value, 0.0752352461, 1e-9);
}

TEST(ChiSquare, AgainstGivenProbabilities) {
  const std::array<std::uint64_t, 3> c{50, 30, 20};
  const std::array<double, 3> p{0.5, 0.3, 0.2};
  const ChiSquare r = chi2_against(c, p);
  EXPECT_NEAR(r.statistic, 0.0, 1e-12);
  EXPECT_EQ(r.dof, 2);
}

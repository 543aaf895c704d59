// Comparing two results: chi-square homogeneity and differences of proportions.
#include <gtest/gtest.h>

#include <stdexcept>

#include "sim/study/compare.hpp"

namespace dicesim {
namespace {

TEST(Compare, NewcombeIntervalPublishedExample) {
  // Newcombe (1998), Statistics in Medicine 17:873, Table II, example (a): 56/70 vs 48/80,
  // method 10 (hybrid score): 0.0524 to 0.3339.
  const Interval ci = difference_interval(56, 70, 48, 80);
  EXPECT_NEAR(ci.lo, 0.0524, 5e-5);
  EXPECT_NEAR(ci.hi, 0.3339, 5e-5);
  // Example (e): 0/10 vs 0/20: -0.1611 to 0.2775.
  const Interval z = difference_interval(0, 10, 0, 20);
  EXPECT_NEAR(z.lo, -0.1611, 5e-5);
  EXPECT_NEAR(z.hi, 0.2775, 5e-5);
}

TEST(Compare, ChiSquareHomogeneityByHand) {
  // 2 x 2: (10, 20) vs (20, 10); every expected count 15: chi2 = 4 * 25 / 15, 1 dof.
  double min_e = 0;
  const ChiSquare c = chi2_homogeneity({10, 20}, {20, 10}, &min_e);
  EXPECT_NEAR(c.statistic, 20.0 / 3.0, 1e-12);
  EXPECT_EQ(c.dof, 1);
  EXPECT_NEAR(c.p_value, 0.009823, 1e-5);
  EXPECT_DOUBLE_EQ(min_e, 15.0);
  // Proportional counts: no evidence at all. Empty categories are left out of the dof.
  const ChiSquare same = chi2_homogeneity({10, 20, 0, 30}, {20, 40, 0, 60});
  EXPECT_NEAR(same.statistic, 0.0, 1e-12);
  EXPECT_EQ(same.dof, 2);
  EXPECT_NEAR(same.p_value, 1.0, 1e-12);
}

TEST(Compare, MatchesFacesByLabel) {
  FaceCounts a{{1, 2, 3, 4, 5, 6}, {100, 200, 300, 400, 500, 600}};
  FaceCounts b{{6, 5, 4, 3, 2, 1}, {60, 50, 40, 30, 20, 10}};  // the same proportions, listed backwards
  const Comparison c = compare_counts(a, b);
  EXPECT_EQ(c.n_a, 2100u);
  EXPECT_EQ(c.n_b, 210u);
  EXPECT_NEAR(c.chi2.statistic, 0.0, 1e-9);
  ASSERT_EQ(c.faces.size(), 6u);
  for (const FaceDifference& f : c.faces) {
    EXPECT_EQ(f.count_a, 100u * static_cast<unsigned>(f.label));
    EXPECT_EQ(f.count_b, 10u * static_cast<unsigned>(f.label));
    EXPECT_NEAR(f.diff, 0.0, 1e-12);
    EXPECT_LT(f.ci95.lo, 0.0);
    EXPECT_GT(f.ci95.hi, 0.0);
  }
  EXPECT_THROW(compare_counts(a, FaceCounts{{1, 2, 3, 4, 5, 7}, {1, 1, 1, 1, 1, 1}}), std::invalid_argument);
}

TEST(Compare, DetectsARealDifference) {
  // A die with P(6) = 0.27 against a fair one, 500 throws each: clearly different on face 6.
  FaceCounts biased{{1, 2, 3, 4, 5, 6}, {43, 83, 74, 85, 81, 135}};
  FaceCounts fair{{1, 2, 3, 4, 5, 6}, {84, 83, 83, 83, 83, 84}};
  const Comparison c = compare_counts(biased, fair);
  EXPECT_LT(c.chi2.p_value, 1e-3);
  EXPECT_GT(c.faces[5].ci95.lo, 0.0);   // face 6 more often in the biased die
  EXPECT_LT(c.faces[0].ci95.hi, 0.0);   // face 1 less often
}

}  // namespace
}  // namespace dicesim

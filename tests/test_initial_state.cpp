// The throw's randomness: a pure function of (seed, toss index), with the stated distributions.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/models/initial_state.hpp"
#include "sim/study/statistics.hpp"
#include "sim/models/toss_random.hpp"

using namespace dicesim;

TEST(TossRandom, SameSeedAndIndexSameNumbers) {
  TossRandom a(42, 7), b(42, 7), c(42, 8), d(43, 7);
  for (int i = 0; i < 20; ++i) {
    const double x = a.uniform();
    EXPECT_EQ(x, b.uniform());
    EXPECT_NE(x, c.uniform());
    EXPECT_NE(x, d.uniform());
  }
}

TEST(TossRandom, HighBitsOfSeedAndIndexMatter) {
  TossRandom a(1, 5), b(1 + (1ULL << 40), 5), c(1, 5 + (1ULL << 40));
  const double x = a.uniform();
  EXPECT_NE(x, b.uniform());
  EXPECT_NE(x, c.uniform());
}

TEST(TossRandom, UniformOpenIntervalMeanAndVariance) {
  // 1e5 draws: mean 1/2 with sd sqrt(1/12/n) = 9.1e-4; allow 4 sd. Variance 1/12 likewise.
  double s = 0, s2 = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    TossRandom r(3, static_cast<std::uint64_t>(i));
    const double u = r.uniform();
    ASSERT_GT(u, 0.0);
    ASSERT_LT(u, 1.0);
    s += u;
    s2 += u * u;
  }
  const double mean = s / n, var = s2 / n - mean * mean;
  EXPECT_NEAR(mean, 0.5, 4 * std::sqrt(1.0 / 12.0 / n));
  // Var of u^2 is 4/45; sd of the variance estimate ~ sqrt((1/80 - 1/144)/n) ~ 2.4e-4.
  EXPECT_NEAR(var, 1.0 / 12.0, 4 * 2.4e-4);
}

TEST(TossRandom, NormalMomentsAndTail) {
  TossRandom r(9, 0);
  const int n = 200000;
  double s = 0, s2 = 0;
  int beyond2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = r.normal();
    s += x;
    s2 += x * x;
    beyond2 += std::abs(x) > 2.0;
  }
  EXPECT_NEAR(s / n, 0.0, 4.0 / std::sqrt(n));
  EXPECT_NEAR(s2 / n, 1.0, 4.0 * std::sqrt(2.0 / n));
  const Interval ci = wilson_interval(static_cast<std::uint64_t>(beyond2), n, 3.29);  // 99.9%
  const double p_true = 0.04550026389635842;
  EXPECT_LE(ci.lo, p_true);
  EXPECT_GE(ci.hi, p_true);
}

TEST(InitialState, UniformRotationIsHaar) {
  // Under the Haar measure the body z axis is uniform on the sphere: its world z component is
  // uniform on [-1, 1]; check the six-bin counts with chi-square at the 0.1% level.
  ThrowDef t;
  std::array<std::uint64_t, 6> bins{};
  for (std::uint64_t i = 0; i < 60000; ++i) {
    const InitialState s = draw_initial_state(t, 11, i);
    ASSERT_NEAR((s.orientation.transpose() * s.orientation - Mat3::Identity()).norm(), 0.0, 1e-12);
    ASSERT_NEAR(s.orientation.determinant(), 1.0, 1e-12);
    const double z = s.orientation(2, 2);
    bins[static_cast<std::size_t>(std::min(5.0, std::floor((z + 1.0) * 3.0)))]++;
  }
  EXPECT_GT(chi2_uniform(bins).p_value, 1e-3);
}

TEST(InitialState, FixedEulerIsZXZ) {
  ThrowDef t;
  t.orientation.kind = OrientationKind::Fixed;
  t.orientation.euler_deg = Vec3(0.0, 90.0, 0.0);
  const InitialState s = draw_initial_state(t, 1, 0);
  // Rx(90 deg) takes the body z axis to world -y.
  EXPECT_NEAR((s.orientation * Vec3::UnitZ() - Vec3(0, -1, 0)).norm(), 0.0, 1e-15);
}

TEST(InitialState, DistributionsFollowTheScene) {
  ThrowDef t;
  t.height = {1.0, 0.2};
  t.velocity = {Vec3(0.5, 0, 0), Vec3(0.1, 0.2, 0.0)};
  t.spin.kind = SpinKind::RandomAxis;
  t.spin.magnitude = {30.0, 0.0};
  const int n = 20000;
  double h = 0, vx = 0, vz_max = 0;
  for (int i = 0; i < n; ++i) {
    const InitialState s = draw_initial_state(t, 5, static_cast<std::uint64_t>(i));
    h += s.com_position.z();
    vx += s.velocity.x();
    vz_max = std::max(vz_max, std::abs(s.velocity.z()));
    ASSERT_NEAR(s.omega.norm(), 30.0, 1e-12);
    ASSERT_EQ(s.com_position.x(), 0.0);
  }
  EXPECT_NEAR(h / n, 1.0, 4 * 0.2 / std::sqrt(n));
  EXPECT_NEAR(vx / n, 0.5, 4 * 0.1 / std::sqrt(n));
  EXPECT_EQ(vz_max, 0.0);  // sd 0: fixed
}

TEST(InitialState, OctantAxisPointsIntoPositiveOctant) {
  ThrowDef t;
  t.spin.kind = SpinKind::OctantAxis;
  t.spin.magnitude = {10.0, 0.0};
  for (std::uint64_t i = 0; i < 1000; ++i) {
    const InitialState s = draw_initial_state(t, 2, i);
    ASSERT_GT(s.omega.minCoeff(), 0.0);
    ASSERT_NEAR(s.omega.norm(), 10.0, 1e-12);
  }
}

TEST(InitialState, StaticDrawIsTheFullDrawsOrientationAndHeight) {
  ThrowDef t;  // the defaults: uniform orientation, normal height, velocity and spin
  for (std::uint64_t i = 0; i < 1000; ++i) {
    const InitialState full = draw_initial_state(t, 4, i);
    const InitialState part = draw_initial_state(t, 4, i, /*motion=*/false);
    ASSERT_EQ(part.orientation, full.orientation);
    ASSERT_EQ(part.com_position, full.com_position);
    ASSERT_EQ(part.velocity, Vec3::Zero());
    ASSERT_EQ(part.omega, Vec3::Zero());
    ASSERT_NE(full.omega, Vec3::Zero());
  }
}

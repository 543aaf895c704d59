// Restitution from drop measurements: the seed's Tables 4-5 and synthetic tracks with known e.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "sim/study/restitution_fit.hpp"

namespace dicesim {
namespace {

// Tables 4 and 5 of the seed (sec. 5.1).
const std::vector<double> kSteelIn{6.2556, 6.5341, 6.7341, 6.3472, 6.1022, 6.4235};
const std::vector<double> kSteelOut{3.1422, 3.0543, 3.2453, 3.1254, 2.9583, 3.1654};
const std::vector<double> kAluIn{6.3721, 6.1352, 6.2412, 6.1252, 6.2315, 6.4312};
const std::vector<double> kAluOut{3.3253, 3.5423, 3.4831, 3.4081, 3.3462, 3.5312};

TEST(RestitutionPairs, SeedTables4And5) {
  const RestitutionEstimate steel = restitution_from_pairs(kSteelIn, kSteelOut);
  const RestitutionEstimate alu = restitution_from_pairs(kAluIn, kAluOut);
  EXPECT_EQ(steel.n, 6u);
  EXPECT_NEAR(steel.restitution, 0.487, 0.0005);  // PHYSICS.md erratum 5
  EXPECT_NEAR(alu.restitution, 0.550, 0.0005);
  for (const auto* e : {&steel, &alu}) {
    EXPECT_LT(e->ci95.lo, e->restitution);
    EXPECT_GT(e->ci95.hi, e->restitution);
    // t(0.975, 5) = 2.5706: the half-width is that many standard errors.
    EXPECT_NEAR(e->ci95.half_width(), 2.5706 * e->sd / std::sqrt(6.0), 1e-4);
  }
  // The two materials differ: the intervals do not overlap (the seed's text prints one value for both).
  EXPECT_LT(steel.ci95.hi, alu.ci95.lo);
  // Signs are ignored: velocities instead of speeds give the same answer.
  std::vector<double> neg_in;
  for (double v : kSteelIn) neg_in.push_back(-v);
  EXPECT_DOUBLE_EQ(restitution_from_pairs(neg_in, kSteelOut).restitution, steel.restitution);
}

TEST(RestitutionPairs, RejectsTooFewOrBadPairs) {
  EXPECT_THROW(restitution_from_pairs({6.0}, {3.0}), std::invalid_argument);
  EXPECT_THROW(restitution_from_pairs({6.0, 0.0}, {3.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(restitution_from_pairs({6.0, NAN}, {3.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(restitution_from_pairs({6.0, 5.0}, {3.0}), std::invalid_argument);
}

// Height of a ball dropped from h0 (at rest) bouncing with restitution e, sampled at `rate`
// until the end of the `flights`-th flight after the first impact (caught mid-air at the apex).
struct Track {
  std::vector<double> t, z;
};
Track bouncing_track(double h0, double e, double rate, int impacts, double noise_sd, unsigned seed, double t0 = 0.013) {
  const double g = 9.81;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_sd);
  // Impact instants and rebound speeds.
  std::vector<double> t_imp{std::sqrt(2.0 * h0 / g)};
  std::vector<double> v_up{e * g * t_imp[0]};
  for (int k = 1; k < impacts; ++k) {
    t_imp.push_back(t_imp.back() + 2.0 * v_up.back() / g);
    v_up.push_back(e * v_up.back());
  }
  const double t_end = t_imp.back() + v_up.back() / g;  // apex after the last impact
  Track tr;
  for (double t = t0; t < t_end; t += 1.0 / rate) {
    double z;
    if (t < t_imp[0]) {
      z = h0 - 0.5 * g * t * t;
    } else {
      std::size_t k = 0;
      while (k + 1 < t_imp.size() && t >= t_imp[k + 1]) ++k;
      const double u = t - t_imp[k];
      z = v_up[k] * u - 0.5 * g * u * u;
    }
    tr.t.push_back(t);
    tr.z.push_back(z + (noise_sd > 0 ? noise(rng) : 0.0));
  }
  return tr;
}

TEST(RestitutionTrack, ExactParabolasGiveExactRatios) {
  const Track tr = bouncing_track(0.5, 0.6, 240.0, 4, 0.0, 1);
  const TrackFit f = restitution_from_track(tr.t, tr.z);
  ASSERT_EQ(f.impacts.size(), 4u);
  for (const TrackImpact& i : f.impacts) {
    EXPECT_NEAR(i.ratio, 0.6, 1e-6);
    EXPECT_NEAR(i.g_before, 9.81, 1e-6);
  }
  EXPECT_NEAR(f.impacts[0].t, std::sqrt(2.0 * 0.5 / 9.81), 1e-6);
  EXPECT_NEAR(f.impacts[0].v_in, -std::sqrt(2.0 * 9.81 * 0.5), 1e-6);
  EXPECT_NEAR(f.estimate.restitution, 0.6, 1e-6);
}

TEST(RestitutionTrack, NoisyVideoTrack) {
  // 0.5 mm of noise at 240 frames/s (a slow-motion phone video), three impacts, e = 0.55.
  const Track tr = bouncing_track(0.8, 0.55, 240.0, 3, 0.0005, 7);
  const TrackFit f = restitution_from_track(tr.t, tr.z);
  ASSERT_GE(f.impacts.size(), 2u);
  EXPECT_LE(f.estimate.ci95.lo, 0.55);
  EXPECT_GE(f.estimate.ci95.hi, 0.55);
  EXPECT_NEAR(f.estimate.restitution, 0.55, 0.02);
}

TEST(RestitutionTrack, RejectsTracksWithoutTwoImpacts) {
  const Track one = bouncing_track(0.5, 0.6, 240.0, 1, 0.0, 1);
  EXPECT_THROW(restitution_from_track(one.t, one.z), std::invalid_argument);
  EXPECT_THROW(restitution_from_track({0, 1, 2}, {1, 0, 1}), std::invalid_argument);
  EXPECT_THROW(restitution_from_track({0, 2, 1, 3, 4, 5, 6, 7, 8}, {0, 0, 0, 0, 0, 0, 0, 0, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace dicesim

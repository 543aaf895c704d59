// Mass properties of boxes cut by planes: exact values derived by hand in the comments, the
// seed's three dice, the aluminium fraction that maximises the COM offset, clipping edge cases,
// and random cuts bracketed by a grid.
#include "sim/body/mass_properties.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace dicesim {
namespace {

constexpr double kSteel = 7848.0;      // kg/m^3 (PHYSICS.md, erratum 8)
constexpr double kAluminium = 2714.3;  // kg/m^3
constexpr double kEdge = 0.03;         // m, the seed's cube
constexpr double kHalf = kEdge / 2.0;
constexpr double kRel = 1e-12;         // relative tolerance of "exact" results

const std::map<std::string, MaterialDef> kMaterials = {
    {"steel", MaterialDef{kSteel, 0.487, 0.3}},
    {"aluminium", MaterialDef{kAluminium, 0.550, 0.3}},
};

// Box [lo, hi] uncut: V = prod(size), int x dV = V c, int x x^T dV = V (c c^T + diag(size^2) / 12)
// (a centred interval of length L has int t^2 dt = L^3 / 12).
VolumeMoments box_moments(const Vec3& lo, const Vec3& hi) {
  const Vec3 size = hi - lo;
  const Vec3 c = 0.5 * (lo + hi);
  VolumeMoments m;
  m.volume = size.prod();
  m.first = m.volume * c;
  m.second = m.volume * (c * c.transpose() + Mat3(size.cwiseAbs2().asDiagonal()) / 12.0);
  return m;
}

// Compares moments on the scale of a reference volume V and length L (first ~ V L, second ~ V L^2).
void expect_moments_near(const VolumeMoments& actual, const VolumeMoments& expected, double volume, double length,
                         double rel = kRel) {
  EXPECT_NEAR(actual.volume, expected.volume, rel * volume);
  EXPECT_LE((actual.first - expected.first).cwiseAbs().maxCoeff(), rel * volume * length)
      << "first\n" << actual.first.transpose() << "\nexpected\n" << expected.first.transpose();
  EXPECT_LE((actual.second - expected.second).cwiseAbs().maxCoeff(), rel * volume * length * length)
      << "second\n" << actual.second << "\nexpected\n" << expected.second;
}

void expect_matrix_near(const Mat3& actual, const Mat3& expected, double tol) {
  EXPECT_LE((actual - expected).cwiseAbs().maxCoeff(), tol) << "actual\n" << actual << "\nexpected\n" << expected;
}

// The principal frame diagonalises the inertia, is orthonormal and right-handed, moments ascending.
void expect_valid_principal_frame(const MassProperties& mp) {
  const double scale = mp.inertia.trace();
  const Mat3& axes = mp.principal_axes;
  expect_matrix_near(axes.transpose() * axes, Mat3::Identity(), 1e-13);
  EXPECT_NEAR(axes.determinant(), 1.0, 1e-13);
  expect_matrix_near(axes.transpose() * mp.inertia * axes, Mat3(mp.principal_moments.asDiagonal()), kRel * scale);
  EXPECT_LE(mp.principal_moments(0), mp.principal_moments(1));
  EXPECT_LE(mp.principal_moments(1), mp.principal_moments(2));
}

// A seed die: 30 mm aluminium cube with one steel region.
DieDef seed_die(const std::vector<HalfSpace>& steel_cuts) {
  DieDef die;
  die.size = Vec3::Constant(kEdge);
  die.base_material = "aluminium";
  die.regions = {RegionDef{"steel", steel_cuts}};
  return die;
}

// ---------------------------------------------------------------------------------------------
// Clipping

TEST(ClippedAabbMoments, UncutBoxMatchesClosedForm) {
  const Vec3 lo(-0.012, -0.02, 0.001), hi(0.018, 0.005, 0.026);
  expect_moments_near(clipped_aabb_moments(lo, hi, {}), box_moments(lo, hi), (hi - lo).prod(), 0.03);
}

TEST(ClippedAabbMoments, PlaneMissingOrTouchingFromOutsideChangesNothing) {
  const Vec3 lo(-0.012, -0.02, 0.001), hi(0.018, 0.005, 0.026);
  const VolumeMoments whole = box_moments(lo, hi);
  const std::vector<std::vector<HalfSpace>> cases = {
      {{Vec3(1, 0, 0), 0.05}},                       // far beyond +x
      {{Vec3(1, 0, 0), hi.x()}},                     // the +x face itself
      {{Vec3(1, 0, 1), hi.x() + hi.z()}},            // touches the (+x, +z) edge only
      {{Vec3(-1, -1, -1), -(lo.x() + lo.y() + lo.z())}},  // touches the lo corner only
      {{Vec3(0, 3, 4), 5.0}},                        // far away, non-unit normal
  };
  for (const auto& cuts : cases) expect_moments_near(clipped_aabb_moments(lo, hi, cuts), whole, whole.volume, 0.03);
}

TEST(ClippedAabbMoments, PlaneRemovingEverythingGivesZeros) {
  const Vec3 lo(-0.012, -0.02, 0.001), hi(0.018, 0.005, 0.026);
  const std::vector<std::vector<HalfSpace>> cases = {
      {{Vec3(1, 0, 0), -0.05}},                   // the box lies wholly beyond the plane
      {{Vec3(1, 0, 0), lo.x()}},                  // only the -x face is left: volume 0
      {{Vec3(1, 1, 1), lo.x() + lo.y() + lo.z()}},  // only the lo corner is left
      {{Vec3(1, 0, 0), 0.0}, {Vec3(-1, 0, 0), 0.0}},  // x <= 0 and x >= 0: the plane x = 0
  };
  for (const auto& cuts : cases) {
    const VolumeMoments m = clipped_aabb_moments(lo, hi, cuts);
    EXPECT_EQ(m.volume, 0.0);
    EXPECT_EQ(m.first, Vec3::Zero());
    EXPECT_EQ(m.second, Mat3::Zero());
  }
}

TEST(ClippedAabbMoments, CornerCutIsTetrahedron) {
  // Cut (x - lo).(1,1,1) <= s at the lo corner leaves the tetrahedron lo + {0, s e_x, s e_y, s e_z}.
  // With u = x - lo its vertices are 0 and s e_i: sum v = s (1,1,1), sum v v^T = s^2 1, so
  //   V = s^3 / 6,  int u dV = V s/4 (1,1,1),  int u u^T dV = V s^2 / 20 (1 + (1,1,1)(1,1,1)^T);
  // shifting by lo: int x = V lo + int u,  int x x^T = int u u^T + lo (int u)^T + (int u) lo^T + V lo lo^T.
  const Vec3 lo(0.01, -0.02, 0.005), hi = lo + Vec3(0.03, 0.04, 0.05);
  const double s = 0.01;
  const Vec3 ones = Vec3::Ones();
  VolumeMoments expected;
  expected.volume = s * s * s / 6.0;
  const Vec3 first_u = expected.volume * s / 4.0 * ones;
  const Mat3 second_u = expected.volume * s * s / 20.0 * (Mat3::Identity() + ones * ones.transpose());
  expected.first = expected.volume * lo + first_u;
  expected.second = second_u + lo * first_u.transpose() + first_u * lo.transpose() + expected.volume * lo * lo.transpose();
  // Non-unit normal on purpose: (2,2,2).x <= 2 (lo.(1,1,1) + s) is the same half-space.
  const HalfSpace cut{Vec3(2, 2, 2), 2.0 * (lo.sum() + s)};
  expect_moments_near(clipped_aabb_moments(lo, hi, {cut}), expected, expected.volume, 0.05);
}

TEST(ClippedAabbMoments, TwoCutsGiveQuarterBox) {
  // x <= 0 and y <= 0 keep [-hx, 0] x [-hy, 0] x [-hz, hz] of the centred box.
  const Vec3 size(0.03, 0.02, 0.04);
  const Vec3 half = 0.5 * size;
  const VolumeMoments expected = box_moments(-half, Vec3(0.0, 0.0, half.z()));
  const VolumeMoments m = clipped_box_moments(size, {{Vec3(1, 0, 0), 0.0}, {Vec3(0, 5, 0), 0.0}});
  expect_moments_near(m, expected, size.prod(), 0.04);
  EXPECT_NEAR(m.volume, size.prod() / 4.0, kRel * size.prod());
}

TEST(ClippedAabbMoments, PlanesThroughCornersCutExactly) {
  const Vec3 size = Vec3::Constant(kEdge);
  const double a = kEdge, h = kHalf, volume = a * a * a;
  // x >= z, i.e. (-1,0,1).x <= 0: through 4 corners and the two y-edges at x = z = +-h. The kept prism
  // has the triangle T = {x >= z} of [-h,h]^2 (vertices (-h,-h), (h,-h), (h,h)) as cross-section:
  //   V = a a^2/2;  int x dV = a int_{-h}^{h} x (x + h) dx = a 2h^3/3 = a^4/12;  int z dV = -a^4/12;
  //   int x^2 dV = a int x^2 (x + h) dx = a h 2h^3/3 = a^5/24, likewise int z^2 dV = a^5/24;
  //   int y^2 dV = (a^3/12) (a^2/2) = a^5/24;  int xz dV = 0 (swapping x and z maps the prism onto
  //   the other half, and int xz = 0 over the cube);  y-products vanish by y -> -y symmetry.
  VolumeMoments prism;
  prism.volume = volume / 2.0;
  prism.first = Vec3(std::pow(a, 4) / 12.0, 0.0, -std::pow(a, 4) / 12.0);
  prism.second = Mat3::Identity() * std::pow(a, 5) / 24.0;
  const VolumeMoments half = clipped_box_moments(size, {{Vec3(-1, 0, 1), 0.0}});
  expect_moments_near(half, prism, volume, a);
  EXPECT_NEAR(half.volume, volume / 2.0, 1e-15 * volume);  // "exactly" half: a few ulps

  // x + y + z <= h: through the 3 corners next to (h,h,h); cuts off the tetrahedron with legs a
  // at that corner, volume a^3/6, leaving 5/6 of the cube.
  EXPECT_NEAR(clipped_box_moments(size, {{Vec3(1, 1, 1), h}}).volume, 5.0 * volume / 6.0, 1e-15 * volume);
}

TEST(ClippedAabbMoments, TinyBoxAtADieCornerIsSplitExactly) {
  // The model compiler weighs a corner's materials by a box of side 1e-6 a at the corner, far from
  // the origin on its own scale. Die 3's plane x = z halves the box at corner (h, h, h) (by the
  // x <-> z mirror symmetry) and misses the one at (h, -h, -h), where x - z = 2h.
  const double e = 1e-6 * kEdge, h = kHalf;
  const HalfSpace steel{Vec3(-1, 0, 1), 0.0};
  // Compare with the stored boxes' volumes: h - e is rounded at the scale of h, so an edge is e only
  // to ~1e-10 relative.
  const Vec3 lo = Vec3::Constant(h - e), hi = Vec3::Constant(h);
  const double v = (hi - lo).prod();
  EXPECT_NEAR(clipped_aabb_moments(lo, hi, {steel}).volume, 0.5 * v, 1e-12 * v);
  const Vec3 lo2(h - e, -h, -h), hi2(h, -h + e, -h + e);
  const double v2 = (hi2 - lo2).prod();
  EXPECT_NEAR(clipped_aabb_moments(lo2, hi2, {steel}).volume, v2, 1e-12 * v2);
}

TEST(ClippedAabbMoments, CoplanarDuplicateCutsCountOnce) {
  const Vec3 size(0.03, 0.02, 0.04);
  const Vec3 half = 0.5 * size;
  const VolumeMoments expected = box_moments(-half, Vec3(0.0, half.y(), half.z()));
  const VolumeMoments m =
      clipped_box_moments(size, {{Vec3(1, 0, 0), 0.0}, {Vec3(1, 0, 0), 0.0}, {Vec3(2, 0, 0), 0.0}, {Vec3(1, 0, 0), 1e-20}});
  expect_moments_near(m, expected, size.prod(), 0.04);
}

TEST(ClippedAabbMoments, RegionsPlusComplementsMakeTheWholeBox) {
  // Box = (P1 and P2) + (not P1) + (P1 and not P2), for random planes through the box.
  const Vec3 lo(-0.012, -0.02, 0.001), hi(0.018, 0.005, 0.026);
  const VolumeMoments whole = box_moments(lo, hi);
  std::mt19937_64 rng(12345);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit;
  auto random_cut = [&] {
    const Vec3 n(gauss(rng), gauss(rng), gauss(rng));
    const Vec3 p = lo + (hi - lo).cwiseProduct(Vec3(unit(rng), unit(rng), unit(rng)));
    return HalfSpace{n, n.dot(p)};
  };
  auto flip = [](const HalfSpace& c) { return HalfSpace{-c.normal, -c.offset}; };
  for (int trial = 0; trial < 50; ++trial) {
    const HalfSpace p1 = random_cut(), p2 = random_cut();
    const VolumeMoments parts[] = {clipped_aabb_moments(lo, hi, {p1, p2}), clipped_aabb_moments(lo, hi, {flip(p1)}),
                                   clipped_aabb_moments(lo, hi, {p1, flip(p2)})};
    VolumeMoments sum;
    for (const VolumeMoments& part : parts) {
      EXPECT_GE(part.volume, 0.0);
      sum.volume += part.volume;
      sum.first += part.first;
      sum.second += part.second;
    }
    expect_moments_near(sum, whole, whole.volume, 0.03);
  }
}

// Grid bracket of the exact integrals over box [lo, hi] cut by `cuts`. A cell that no plane
// crosses is wholly in or out, and its integrals are exact (int x over a cell = V c,
// int x_i x_j = V (c_i c_j + delta_ij h_i^2 / 12)). A cell a plane may cross (|n.c - d| <= the
// cell's half-extent along n) is split into 8 while `depth` allows; at the last level the part
// inside integrates f to something in [V min(0, min f), V max(0, max f)] over the cell, so we add
// the middle of that interval to the estimate and its half-width to the slack.
// Hence |exact - estimate| <= slack, by construction, whatever the resolution.
struct GridBracket {
  VolumeMoments estimate, slack;
};

void bracket_cell(const Vec3& c, const Vec3& h, const std::vector<HalfSpace>& cuts, int depth, GridBracket& g) {
  bool outside = false, crossed = false;
  for (const HalfSpace& cut : cuts) {
    const double s = cut.normal.dot(c) - cut.offset;
    const double reach = 0.5 * cut.normal.cwiseAbs().dot(h);
    outside = outside || s > reach;
    crossed = crossed || std::abs(s) <= reach;
  }
  if (outside) return;
  const double volume = h.prod();
  if (!crossed) {
    g.estimate.volume += volume;
    g.estimate.first += volume * c;
    g.estimate.second += volume * (c * c.transpose() + Mat3(h.cwiseAbs2().asDiagonal()) / 12.0);
    return;
  }
  if (depth > 0) {
    for (int octant = 0; octant < 8; ++octant) {
      const Vec3 side((octant & 1) ? 1 : -1, (octant & 2) ? 1 : -1, (octant & 4) ? 1 : -1);
      bracket_cell(c + 0.25 * side.cwiseProduct(h), 0.5 * h, cuts, depth - 1, g);
    }
    return;
  }
  auto add_uncertain = [&](double& estimate, double& slack, double f_min, double f_max) {
    const double low = volume * std::min(0.0, f_min), high = volume * std::max(0.0, f_max);
    estimate += 0.5 * (low + high);
    slack += 0.5 * (high - low);
  };
  const Vec3 low = c - 0.5 * h, high = c + 0.5 * h;  // range of each coordinate over the cell
  add_uncertain(g.estimate.volume, g.slack.volume, 1.0, 1.0);
  for (int a = 0; a < 3; ++a) {
    add_uncertain(g.estimate.first(a), g.slack.first(a), low(a), high(a));
    for (int b = 0; b < 3; ++b) {
      double f_min, f_max;
      if (a == b) {
        f_max = std::max(low(a) * low(a), high(a) * high(a));
        f_min = (low(a) <= 0.0 && high(a) >= 0.0) ? 0.0 : std::min(low(a) * low(a), high(a) * high(a));
      } else {
        const double p[] = {low(a) * low(b), low(a) * high(b), high(a) * low(b), high(a) * high(b)};
        f_min = *std::min_element(std::begin(p), std::end(p));
        f_max = *std::max_element(std::begin(p), std::end(p));
      }
      add_uncertain(g.estimate.second(a, b), g.slack.second(a, b), f_min, f_max);
    }
  }
}

// n^3 cells, each refined up to `depth` times where a plane may cross it.
GridBracket grid_bracket(const Vec3& lo, const Vec3& hi, const std::vector<HalfSpace>& cuts, int n, int depth) {
  const Vec3 h = (hi - lo) / n;
  GridBracket g;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) bracket_cell(lo + h.cwiseProduct(Vec3(i + 0.5, j + 0.5, k + 0.5)), h, cuts, depth, g);
  return g;
}

TEST(ClippedAabbMoments, RandomCutsLieInsideGridBracket) {
  const Vec3 lo(-0.012, -0.02, 0.001), hi(0.018, 0.005, 0.026);
  const double box_volume = (hi - lo).prod();
  const double rounding = 1e-12;  // relative, for the comparison itself
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit;
  for (int trial = 0; trial < 6; ++trial) {  // 1, 2, 3 planes, twice each
    std::vector<HalfSpace> cuts;
    for (int k = 0; k <= trial % 3; ++k) {
      const Vec3 n = (0.5 + 4.5 * unit(rng)) * Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
      // Through a point of the box's middle half, so that the cuts usually leave something.
      const Vec3 p = lo + (hi - lo).cwiseProduct(Vec3(0.25 + 0.5 * unit(rng), 0.25 + 0.5 * unit(rng), 0.25 + 0.5 * unit(rng)));
      cuts.push_back({n, n.dot(p)});
    }
    const VolumeMoments exact = clipped_aabb_moments(lo, hi, cuts);
    const GridBracket grid = grid_bracket(lo, hi, cuts, 16, 3);  // resolution 128 near the cuts
    SCOPED_TRACE(testing::Message() << "trial " << trial << ", volume fraction " << exact.volume / box_volume);
    EXPECT_LE(grid.slack.volume, 0.01 * box_volume);  // the bracket is tight enough to mean something
    EXPECT_LE(std::abs(exact.volume - grid.estimate.volume), grid.slack.volume + rounding * box_volume);
    for (int a = 0; a < 3; ++a) {
      EXPECT_LE(std::abs(exact.first(a) - grid.estimate.first(a)), grid.slack.first(a) + rounding * box_volume * 0.03);
      for (int b = 0; b < 3; ++b)
        EXPECT_LE(std::abs(exact.second(a, b) - grid.estimate.second(a, b)),
                  grid.slack.second(a, b) + rounding * box_volume * 0.03 * 0.03);
    }
  }
}

TEST(ClippedAabbMoments, InvalidInputThrows) {
  const Vec3 size = Vec3::Constant(kEdge);
  EXPECT_THROW(clipped_box_moments(size, {{Vec3::Zero(), 0.0}}), std::invalid_argument);
  // Even after an earlier cut has already emptied the box.
  EXPECT_THROW(clipped_box_moments(size, {{Vec3::UnitX(), -1.0}, {Vec3::Zero(), 0.0}}), std::invalid_argument);
  EXPECT_THROW(clipped_box_moments(size, {{Vec3(std::nan(""), 0, 1), 0.0}}), std::invalid_argument);
  EXPECT_THROW(clipped_box_moments(size, {{Vec3::UnitZ(), std::numeric_limits<double>::infinity()}}), std::invalid_argument);
  EXPECT_THROW(clipped_aabb_moments(Vec3::Ones(), Vec3::Zero(), {}), std::invalid_argument);
}

TEST(ClippedBoxMoments, IsTheCentredBox) {
  const Vec3 size(0.03, 0.02, 0.04);
  expect_moments_near(clipped_box_moments(size, {}), box_moments(-0.5 * size, 0.5 * size), size.prod(), 0.04);
}

TEST(InertiaFromSecondMoment, IsDensityTimesTraceMinusSecond) {
  Mat3 s;
  s << 1, 2, 3, 2, 5, 6, 3, 6, 9;
  Mat3 expected;
  expected << 28, -4, -6, -4, 20, -12, -6, -12, 12;  // 2 (15 I - S)
  expect_matrix_near(inertia_from_second_moment(s, 2.0), expected, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Mass properties

TEST(MassProperties, HomogeneousCube) {
  // m = rho a^3; about the centre int x^2 dm = m a^2/12 per axis, so I = m (a^2/12 + a^2/12) 1 = m a^2/6 1.
  DieDef die;
  die.size = Vec3::Constant(kEdge);
  die.base_material = "steel";
  const MassProperties mp = compute_mass_properties(die, kMaterials);
  const double m = kSteel * std::pow(kEdge, 3);
  const double i0 = m * kEdge * kEdge / 6.0;
  EXPECT_NEAR(mp.mass, m, kRel * m);
  EXPECT_LE(mp.com.norm(), kRel * kEdge);
  expect_matrix_near(mp.inertia, i0 * Mat3::Identity(), kRel * i0);
  EXPECT_LE((mp.principal_moments - Vec3::Constant(i0)).cwiseAbs().maxCoeff(), kRel * i0);
  EXPECT_EQ(mp.principal_axes, Mat3::Identity());  // all moments equal: identity by convention
}

TEST(MassProperties, SeedDie1HalfSlabs) {
  // Steel z in [0, h], aluminium z in [-h, 0], h = a/2. Each half: mass rho a^2 h, centre z = +-a/4.
  //   m = (rho_s + rho_a) a^3 / 2,   c_z = (rho_s - rho_a) a^3/2 (a/4) / m = (rho_s - rho_a)/(rho_s + rho_a) a/4.
  // About the geometric centre each half has int z^2 dm = M h^2/3 = M a^2/12 and int x^2 dm = M a^2/12,
  // so I_origin = m a^2/6 1 as for a homogeneous cube. Parallel axis, I_com = I_origin - m(|c|^2 1 - c c^T):
  //   I_xx = I_yy = m a^2/6 - m c_z^2,  I_zz = m a^2/6,  no products.  A symmetric top about z.
  const MassProperties mp = compute_mass_properties(seed_die({{Vec3(0, 0, -1), 0.0}}), kMaterials);
  const double a = kEdge;
  const double m = (kSteel + kAluminium) * a * a * a / 2.0;
  const double cz = (kSteel - kAluminium) / (kSteel + kAluminium) * a / 4.0;
  const double i0 = m * a * a / 6.0;
  EXPECT_NEAR(mp.mass, m, kRel * m);
  EXPECT_LE((mp.com - Vec3(0, 0, cz)).norm(), kRel * a);
  const Mat3 expected = Vec3(i0 - m * cz * cz, i0 - m * cz * cz, i0).asDiagonal();
  expect_matrix_near(mp.inertia, expected, kRel * i0);
  EXPECT_LE((mp.principal_moments - Vec3(i0 - m * cz * cz, i0 - m * cz * cz, i0)).cwiseAbs().maxCoeff(), kRel * i0);
  expect_valid_principal_frame(mp);
  expect_matrix_near(mp.principal_axes, Mat3::Identity(), 1e-12);  // geometric axes, x, y, z
  // Numbers, to catch a slip in the formulas themselves: m = 10562.3 * 1.35e-5 kg, c_z = 3.6453 mm.
  EXPECT_NEAR(m, 0.14259105, 1e-10);
  EXPECT_NEAR(cz, 0.0036453, 1e-7);
}

TEST(MassProperties, SeedDie2Slabs24And6) {
  // Steel z in [-0.009, h] (24 mm), aluminium z in [-h, -0.009] (6 mm). A slab [z0, z1] of density rho:
  //   M = rho a^2 (z1 - z0),  int z dm = M (z0 + z1)/2,  int z^2 dm = M (z0^2 + z0 z1 + z1^2)/3,
  //   int x^2 dm = int y^2 dm = M a^2/12.
  // c_z = sum M zbar / m;  I_zz = m a^2/6;  I_xx = I_yy = m a^2/12 + sum int z^2 dm - m c_z^2.
  const MassProperties mp = compute_mass_properties(seed_die({{Vec3(0, 0, -1), 0.009}}), kMaterials);
  const double a = kEdge, h = kHalf;
  struct Slab {
    double rho, z0, z1;
  };
  const Slab slabs[] = {{kSteel, -0.009, h}, {kAluminium, -h, -0.009}};
  double m = 0.0, mz = 0.0, mzz = 0.0;
  for (const Slab& s : slabs) {
    const double mass = s.rho * a * a * (s.z1 - s.z0);
    m += mass;
    mz += mass * (s.z0 + s.z1) / 2.0;
    mzz += mass * (s.z0 * s.z0 + s.z0 * s.z1 + s.z1 * s.z1) / 3.0;
  }
  const double cz = mz / m;
  const double i_side = m * a * a / 12.0 + mzz - m * cz * cz, i_axis = m * a * a / 6.0;
  EXPECT_NEAR(mp.mass, m, kRel * m);
  EXPECT_LE((mp.com - Vec3(0, 0, cz)).norm(), kRel * a);
  expect_matrix_near(mp.inertia, Vec3(i_side, i_side, i_axis).asDiagonal(), kRel * i_axis);
  EXPECT_LE((mp.principal_moments - Vec3(i_side, i_side, i_axis)).cwiseAbs().maxCoeff(), kRel * i_axis);
  expect_valid_principal_frame(mp);
  expect_matrix_near(mp.principal_axes, Mat3::Identity(), 1e-12);
  // The same die from the fraction formula of the r* test (r = 0.2): c_z = a/2 (rho_s - rho_a) r (1-r) / (rho_a r + rho_s (1-r)).
  EXPECT_NEAR(cz, a / 2 * (kSteel - kAluminium) * 0.2 * 0.8 / (kAluminium * 0.2 + kSteel * 0.8), kRel * a);
}

TEST(MassProperties, SeedDie3DiagonalPrisms) {
  // Steel where x >= z, aluminium where x <= z: two triangular prisms along y. From the prism
  // integrals (PlanesThroughCornersCutExactly): each has int x^2 = int y^2 = int z^2 = a^5/24 and no
  // products about the centre, so I_origin = m a^2/6 1 with m = (rho_s + rho_a) a^3/2. The steel prism
  // has int x = a^4/12, int z = -a^4/12, the aluminium one the opposite, so
  //   c = (c_x, 0, -c_x),  c_x = (rho_s - rho_a) a^4/12 / m = (rho_s - rho_a)/(rho_s + rho_a) a/6.
  // I_com = m a^2/6 1 - m (|c|^2 1 - c c^T) = m a^2/6 1 - m c_x^2 [[1,0,1],[0,2,0],[1,0,1]]:
  //   I_xx = I_zz = m a^2/6 - m c_x^2,  I_yy = m a^2/6 - 2 m c_x^2,  I_xz = -m c_x^2 (non-zero).
  // Eigenvectors: (1,0,-1)/sqrt2 -> m a^2/6 (the COM offset axis, the symmetry axis);
  // (1,0,1)/sqrt2 and y -> m a^2/6 - 2 m c_x^2. A symmetric top.
  const MassProperties mp = compute_mass_properties(seed_die({{Vec3(-1, 0, 1), 0.0}}), kMaterials);
  const double a = kEdge;
  const double m = (kSteel + kAluminium) * a * a * a / 2.0;
  const double cx = (kSteel - kAluminium) / (kSteel + kAluminium) * a / 6.0;
  const double i0 = m * a * a / 6.0, d = m * cx * cx;
  Mat3 expected;
  expected << i0 - d, 0, -d, 0, i0 - 2 * d, 0, -d, 0, i0 - d;
  EXPECT_NEAR(mp.mass, m, kRel * m);
  EXPECT_LE((mp.com - Vec3(cx, 0, -cx)).norm(), kRel * a);
  EXPECT_NEAR(mp.com.x(), -mp.com.z(), kRel * a);  // on the line x = -z, y = 0
  EXPECT_NEAR(mp.com.y(), 0.0, kRel * a);
  expect_matrix_near(mp.inertia, expected, kRel * i0);
  EXPECT_LT(mp.inertia(0, 2), -0.01 * i0);  // a real product of inertia
  EXPECT_LE((mp.principal_moments - Vec3(i0 - 2 * d, i0 - 2 * d, i0)).cwiseAbs().maxCoeff(), kRel * i0);
  EXPECT_EQ(mp.principal_moments(0), mp.principal_moments(1));  // repeated moments are made equal
  expect_valid_principal_frame(mp);
  // The documented choice: y, then (1,0,1)/sqrt2 (the other geometric axes' projection), then the
  // symmetry axis pointing to +x.
  const double r = std::sqrt(0.5);
  Mat3 axes;
  axes << 0, r, r, 1, 0, 0, 0, r, -r;
  expect_matrix_near(mp.principal_axes, axes, 1e-12);
  // The symmetry axis is along the COM offset.
  EXPECT_NEAR(std::abs(mp.principal_axes.col(2).dot(mp.com.normalized())), 1.0, 1e-12);
}

TEST(MassProperties, SlabsAlongXAndYGiveRightHandedGeometricAxes) {
  // Steel x >= 0: moments I_yy = I_zz < I_xx -> axes y, z, x (right-handed as is).
  const MassProperties along_x = compute_mass_properties(seed_die({{Vec3(-1, 0, 0), 0.0}}), kMaterials);
  expect_valid_principal_frame(along_x);
  Mat3 yzx;
  yzx << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  expect_matrix_near(along_x.principal_axes, yzx, 1e-12);
  // Steel y >= 0: I_xx = I_zz < I_yy -> x, z, y is left-handed, so the repeated pair swaps: z, x, y.
  const MassProperties along_y = compute_mass_properties(seed_die({{Vec3(0, -1, 0), 0.0}}), kMaterials);
  expect_valid_principal_frame(along_y);
  Mat3 zxy;
  zxy << 0, 1, 0, 0, 0, 1, 1, 0, 0;
  expect_matrix_near(along_y.principal_axes, zxy, 1e-12);
}

TEST(MassProperties, AluminiumFractionMaximisingComOffset) {
  // Aluminium z in [-h, -h + r a], steel above. From the bottom, centres r a/2 and (1 + r) a/2, so
  //   offset(r) = a/2 (rho_s - rho_a) r (1 - r) / (rho_a r + rho_s (1 - r)).
  // d/dr = 0 <=> rho_s - 2 rho_s r + (rho_s - rho_a) r^2 = 0, whose root in [0, 1] is
  //   r* = (rho_s - sqrt(rho_s rho_a)) / (rho_s - rho_a) = sqrt(k) / (1 + sqrt(k)),  k = rho_s / rho_a.
  const double a = kEdge, h = kHalf;
  const double k = kSteel / kAluminium;
  const double r_star = std::sqrt(k) / (1.0 + std::sqrt(k));
  EXPECT_NEAR(r_star, 0.630, 5e-4);
  EXPECT_NEAR(kSteel - 2 * kSteel * r_star + (kSteel - kAluminium) * r_star * r_star, 0.0, 1e-9 * kSteel);

  auto offset = [&](double r) {
    const MassProperties mp = compute_mass_properties(seed_die({{Vec3(0, 0, -1), h - r * a}}), kMaterials);
    return mp.com.z();
  };
  auto argmax = [&](int steps) {
    int best = 0;
    double best_offset = -1.0;
    for (int i = 0; i <= steps; ++i) {
      const double r = static_cast<double>(i) / steps, z = offset(r);
      EXPECT_NEAR(z, a / 2 * (kSteel - kAluminium) * r * (1 - r) / (kAluminium * r + kSteel * (1 - r)), kRel * a);
      if (z > best_offset) {
        best = i;
        best_offset = z;
      }
    }
    return best;
  };
  const int steps = 1000;
  EXPECT_LE(std::abs(static_cast<double>(argmax(steps)) / steps - r_star), 1.0 / steps);
  EXPECT_EQ(argmax(30), 19);  // 1 mm steps of the 30 mm cube: the seed's sweep peaks at 19/30
}

TEST(MassProperties, ZeroSizeDieHasNoMassAndNoNaN) {
  // The caller (the model compiler) turns this into a scene error; here it must just not be NaN.
  DieDef die = seed_die({{Vec3(0, 0, -1), 0.0}});
  die.size = Vec3(0.03, 0.0, 0.03);
  const MassProperties mp = compute_mass_properties(die, kMaterials);
  EXPECT_EQ(mp.mass, 0.0);
  EXPECT_TRUE(mp.com.allFinite());
  EXPECT_TRUE(mp.inertia.allFinite());
}

TEST(MassProperties, UnknownMaterialThrows) {
  DieDef die = seed_die({{Vec3(0, 0, -1), 0.0}});
  die.regions[0].material = "gold";
  EXPECT_THROW(compute_mass_properties(die, kMaterials), std::out_of_range);
}

}  // namespace
}  // namespace dicesim

// ---- Any convex polytope, meshes, rounding ----------------------------------------------------
#include "sim/body/body.hpp"
#include "sim/body/labels.hpp"
#include "sim/body/rounding.hpp"
#include "sim/body/shape.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {
namespace {

constexpr double kDensity = 1200.0;

Body shaped(const std::string& die_keys, const std::string& extra = "") {
  return build_body(parse_scene("[materials.plastic]\ndensity = 1200.0\n" + extra + "[die]\nmaterial = \"plastic\"\n" +
                                    die_keys,
                                "test"),
                    "test");
}

void expect_isotropic(const MassProperties& mp, double moment, double mass) {
  EXPECT_NEAR(mp.mass, mass, kRel * mass);
  EXPECT_LE(mp.com.norm(), 1e-14);
  expect_matrix_near(mp.inertia, moment * Mat3::Identity(), kRel * moment);
}

// Closed forms by edge a (e.g. Wikipedia's tables of the Platonic solids; I about the centre, the
// same about every axis), a from size = distance between opposite faces (d4: face to vertex):
//   tetrahedron  H = a sqrt(2/3)            V = a^3 / (6 sqrt2)         I = M a^2 / 20
//   cube         a = size                   V = a^3                     I = M a^2 / 6
//   octahedron   inradius a / sqrt6         V = sqrt2 / 3 a^3           I = M a^2 / 10
//   dodecahedron inradius a sqrt(250 + 110 sqrt5) / 20, V = (15 + 7 sqrt5) / 4 a^3,  I = M a^2 (95 + 39 sqrt5) / 300
//   icosahedron  inradius phi^2 a / (2 sqrt3), V = 5 (3 + sqrt5) / 12 a^3,         I = M a^2 phi^2 / 10
TEST(PresetMassProperties, PlatonicSolidsMatchClosedForms) {
  const double s = 0.02, r5 = std::sqrt(5.0), phi = (1.0 + r5) / 2.0;
  struct Case {
    const char* shape;
    double a, volume, moment_per_ma2;
  };
  const double a4 = s * std::sqrt(1.5), a8 = s / 2.0 * std::sqrt(6.0), a12 = s / 2.0 * 20.0 / std::sqrt(250.0 + 110.0 * r5),
               a20 = s / 2.0 * 2.0 * std::sqrt(3.0) / (phi * phi);
  const Case cases[] = {
      {"d4", a4, a4 * a4 * a4 / (6.0 * std::sqrt(2.0)), 1.0 / 20.0},
      {"d6", s, s * s * s, 1.0 / 6.0},
      {"d8", a8, std::sqrt(2.0) / 3.0 * a8 * a8 * a8, 1.0 / 10.0},
      {"d12", a12, (15.0 + 7.0 * r5) / 4.0 * a12 * a12 * a12, (95.0 + 39.0 * r5) / 300.0},
      {"d20", a20, 5.0 * (3.0 + r5) / 12.0 * a20 * a20 * a20, phi * phi / 10.0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.shape);
    const Body b = shaped(std::string("shape = \"") + c.shape + "\"\nsize = 0.02\n");
    const double mass = kDensity * c.volume;
    expect_isotropic(b.mass, c.moment_per_ma2 * mass * c.a * c.a, mass);
  }
}

TEST(PresetMassProperties, D10IsAPyramidSumAndASymmetricTop) {
  // All faces at distance size/2 from the centre: V = sum over faces of area * (size/2) / 3.
  const Body b = shaped("shape = \"d10\"\nsize = 0.02\n");
  double area = 0.0;
  for (std::size_t f = 0; f < b.shape.faces.size(); ++f) area += face_area(b.shape, f);
  const double volume = area * 0.01 / 3.0;
  EXPECT_NEAR(b.mass.mass, kDensity * volume, kRel * kDensity * volume);
  EXPECT_LE(b.mass.com.norm(), 1e-14);
  const Mat3& I = b.mass.inertia;
  EXPECT_NEAR(I(0, 0), I(1, 1), kRel * I(0, 0));
  EXPECT_LE(std::max({std::abs(I(0, 1)), std::abs(I(0, 2)), std::abs(I(1, 2))}), kRel * I(0, 0));
}

TEST(PresetMassProperties, PrismMatchesClosedForm) {
  // Regular n-gon, circumradius R: A = n/2 R^2 sin(2 pi/n), polar moment J = A R^2 / 6 (1 + 2 cos^2(pi/n)).
  for (int n : {3, 5, 8}) {
    const double R = 0.01, L = 0.05;
    const Body b = shaped("shape = \"prism\"\nsides = " + std::to_string(n) + "\nradius = 0.01\nlength = 0.05\n");
    const double area = n / 2.0 * R * R * std::sin(2.0 * kPi / n);
    const double mass = kDensity * area * L;
    const double izz = mass * R * R / 6.0 * (1.0 + 2.0 * std::pow(std::cos(kPi / n), 2));
    const double ixx = izz / 2.0 + mass * L * L / 12.0;
    EXPECT_NEAR(b.mass.mass, mass, kRel * mass);
    expect_matrix_near(b.mass.inertia, Vec3(ixx, ixx, izz).asDiagonal().toDenseMatrix(), kRel * ixx);
  }
}

TEST(SurfaceMoments, ClippingAnyPolytopeMatchesTheBoxClipper) {
  // The general clipper (triangles, caps fanned) against the box clipper, random cuts.
  const Vec3 size(0.03, 0.02, 0.025);
  const Triangles box = shape_triangles(box_shape(size));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<HalfSpace> cuts;
    const int n = 1 + trial % 3;
    for (int k = 0; k < n; ++k) cuts.push_back({Vec3(u(rng), u(rng), u(rng)), 0.01 * u(rng)});
    expect_moments_near(clipped_surface_moments(box, cuts), clipped_box_moments(size, cuts), size.prod(), 0.03);
  }
}

// An L-shaped (non-convex) closed mesh: the unit cube [0,2]x[0,1]x[0,1] plus [0,1]x[1,2]x[0,1].
std::string l_shape_obj() {
  return R"(# an L: three unit cubes
v 0 0 0
v 2 0 0
v 2 1 0
v 1 1 0
v 1 2 0
v 0 2 0
v 0 0 1
v 2 0 1
v 2 1 1
v 1 1 1
v 1 2 1
v 0 2 1
f 1 6 5 4 3 2
f 7 8 9 10 11 12
f 1 2 8 7
f 2 3 9 8
f 3 4 10 9
f 4 5 11 10
f 5 6 12 11
f 6 1 7 12
)";
}

TEST(MeshMassProperties, NonConvexMeshWithARegionIsExact) {
  const std::string path = ::testing::TempDir() + "/l_shape.obj";
  std::ofstream(path) << l_shape_obj();
  const std::string scene = "[materials.plastic]\ndensity = 1000.0\n[materials.lead]\ndensity = 11000.0\n"
                            "[die]\nmaterial = \"plastic\"\nshape = \"mesh\"\nmesh = \"" + path + "\"\nscale = 0.01\n";
  const Body b = build_body(parse_scene(scene, "test"), "test");
  EXPECT_FALSE(b.convex);
  EXPECT_EQ(b.shape.faces.size(), 7u) << "the L's hull is a pentagonal prism";
  // Three cubes of 1 cm (1e-6 m^3) centred at (0.5, 0.5, 0.5), (1.5, 0.5, 0.5), (0.5, 1.5, 0.5) cm.
  EXPECT_NEAR(b.mass.mass, 3e-3, 1e-15);
  EXPECT_LE((b.mass.com - 0.01 * Vec3(2.5 / 3.0, 2.5 / 3.0, 0.5)).norm(), 1e-15);
  // Lead where x <= 0.5 cm: a 0.5 x 2 x 1 cm slab centred at (0.25, 1, 0.5) cm.
  const Body loaded = build_body(
      parse_scene(scene + "[[die.regions]]\nmaterial = \"lead\"\ncuts = [{normal = [1, 0, 0], offset = 0.005}]\n", "test"),
      "test");
  EXPECT_NEAR(loaded.mass.mass, 3e-3 + 10000.0 * 1e-6, 1e-14);
  const Vec3 first = 1e-3 * 0.01 * Vec3(2.5, 2.5, 1.5) + 10000.0 * 1e-6 * 0.01 * Vec3(0.25, 1.0, 0.5);
  EXPECT_LE((loaded.mass.com - first / loaded.mass.mass).norm(), 1e-15);
}

TEST(SurfaceMoments, CutsOfANonConvexSolidCloseEveryCapLoop) {
  // The L cut by y <= 0.5 then by x >= 0.25: one cap per cut, the second cap crossing the first.
  // By hand: y <= 0.5 keeps [0,2]x[0,0.5]x[0,1] (volume 1); x >= 0.25 then [0.25,2]x[0,0.5]x[0,1].
  // Cut the other way, x <= 0.5 keeps [0,0.5]x[0,2]x[0,1] (volume 1), a cap across both arms.
  // And the plane x + y <= 1.25 cuts both arms of the L: its cap is one non-convex region.
  Triangles l;
  std::istringstream in(l_shape_obj());
  std::vector<Vec3> v;
  std::vector<std::vector<int>> f;
  for (std::string line; std::getline(in, line);) {
    std::istringstream w(line);
    std::string k;
    w >> k;
    if (k == "v") {
      Vec3 p;
      w >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    } else if (k == "f") {
      std::vector<int> loop;
      for (int i; w >> i;) loop.push_back(i - 1);
      f.push_back(loop);
    }
  }
  for (const auto& loop : f)
    for (std::size_t k = 1; k + 1 < loop.size(); ++k) l.push_back({v[loop[0]], v[loop[k]], v[loop[k + 1]]});
  EXPECT_NEAR(surface_moments(l).volume, 3.0, 1e-14);
  EXPECT_NEAR(clipped_surface_moments(l, {{Vec3(0, 1, 0), 0.5}}).volume, 1.0, 1e-14);
  EXPECT_NEAR(clipped_surface_moments(l, {{Vec3(0, 1, 0), 0.5}, {Vec3(-1, 0, 0), -0.25}}).volume, 1.75 * 0.5, 1e-14);
  const VolumeMoments slab = clipped_surface_moments(l, {{Vec3(1, 0, 0), 0.5}});
  EXPECT_NEAR(slab.volume, 1.0, 1e-14);
  EXPECT_LE((slab.first - Vec3(0.25, 1.0, 0.5)).norm(), 1e-14);
  // x + y <= 1.25: the triangle x, y >= 0, x + y <= 1.25 (area 1.25^2/2) lies inside the L
  // (it stays within x <= 1 or y <= 1), times height 1.
  EXPECT_NEAR(clipped_surface_moments(l, {{Vec3(1, 1, 0), 1.25}}).volume, 1.25 * 1.25 / 2.0, 1e-14);
  // The plane x + y = 2.5 crosses the L twice (it passes the notch at (1.25, 1.25)): two cap
  // loops. x + y >= 2.5 keeps the two arm tips, triangles of legs 0.5 each; x + y <= 2.5 the rest.
  EXPECT_NEAR(clipped_surface_moments(l, {{Vec3(-1, -1, 0), -2.5}}).volume, 0.25, 1e-14);
  const VolumeMoments rest = clipped_surface_moments(l, {{Vec3(1, 1, 0), 2.5}});
  EXPECT_NEAR(rest.volume, 2.75, 1e-14);
  // Tips' centroids: (2 - 1/6, 1 - 1/6 ... ) i.e. (11/6, 5/6) and (5/6, 11/6): first moment of the
  // rest = whole - tips.
  const Vec3 tips = 0.125 * Vec3(11.0 / 6.0, 5.0 / 6.0, 0.5) + 0.125 * Vec3(5.0 / 6.0, 11.0 / 6.0, 0.5);
  EXPECT_LE((rest.first - (surface_moments(l).first - tips)).norm(), 1e-14);
}

TEST(MeshMassProperties, MeshOfAPresetEqualsThePreset) {
  const Body d20 = shaped("shape = \"d20\"\nsize = 0.02\n");
  std::ostringstream obj;
  obj.precision(17);
  for (const Vec3& p : d20.shape.vertices) obj << "v " << p.x() * 1000 << ' ' << p.y() * 1000 << ' ' << p.z() * 1000 << '\n';
  for (const auto& loop : d20.shape.faces) {
    obj << "f";
    for (int i : loop) obj << ' ' << i + 1 << "//" << i + 1;
    obj << '\n';
  }
  const std::string path = ::testing::TempDir() + "/d20.obj";
  std::ofstream(path) << obj.str();
  const Body mesh = shaped("shape = \"mesh\"\nmesh = \"" + path + "\"\nscale = 0.001\n");
  EXPECT_TRUE(mesh.convex);
  EXPECT_EQ(mesh.shape.faces.size(), 20u);
  EXPECT_NEAR(mesh.mass.mass, d20.mass.mass, kRel * d20.mass.mass);
  expect_matrix_near(mesh.mass.inertia, d20.mass.inertia, kRel * d20.mass.inertia.trace());
  for (std::size_t v = 0; v < mesh.shape.vertices.size(); ++v)
    EXPECT_LE((mesh.shape.vertices[v] - d20.shape.vertices[v]).norm(), 1e-15);
}

// Gauss-Legendre nodes and weights on [0, 1] (n points, Newton on the Legendre polynomial).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.resize(n);
  w.resize(n);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    x[i] = 0.5 * (1.0 - z);
    w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
  }
}

TEST(RoundedPieces, EdgeWedgeMatchesQuadrature) {
  const Vec3 a(0.01, -0.02, 0.005), b(0.03, 0.01, -0.01);
  const Vec3 e = (b - a).normalized();
  const Vec3 u = e.unitOrthogonal();
  const double angle = 1.1;
  const Vec3 v = std::cos(angle) * u + std::sin(angle) * e.cross(u);
  const double r = 0.004, L = (b - a).norm();
  std::vector<double> x, w;
  gauss_legendre(24, x, w);
  VolumeMoments q;
  const Vec3 wdir = e.cross(u);
  for (int i = 0; i < 24; ++i)
    for (int j = 0; j < 24; ++j)
      for (int k = 0; k < 24; ++k) {
        const double s = L * x[i], rho = r * x[j], phi = angle * x[k];
        const double dv = w[i] * w[j] * w[k] * L * r * angle * rho;
        const Vec3 p = a + s * e + rho * (std::cos(phi) * u + std::sin(phi) * wdir);
        q.volume += dv;
        q.first += dv * p;
        q.second += dv * p * p.transpose();
      }
  expect_moments_near(edge_wedge_moments(a, b, u, v, r), q, q.volume, 0.03);
}

TEST(RoundedPieces, CornerSectorMatchesQuadrature) {
  // A tetrahedron corner at p with edges along e1, e2, e3 (not orthogonal): faces (e1, e2),
  // (e2, e3), (e3, e1) with outward normals; the normal cone is the spherical triangle of the three
  // normals, integrated here by mapping the flat triangle of the normals radially onto the sphere:
  // dOmega = h / |x|^3 dA (h the flat triangle's distance from the centre).
  const Vec3 p(0.002, -0.001, 0.003);
  const Vec3 e1 = Vec3(1, 0.2, 0.1).normalized(), e2 = Vec3(0.1, 1, -0.3).normalized(), e3 = Vec3(0.2, 0.3, 1).normalized();
  // Outward normals of the solid cone {p + a e1 + b e2 + c e3 : a, b, c >= 0}.
  auto outward = [&](const Vec3& x, const Vec3& y, const Vec3& other) {
    Vec3 n = x.cross(y).normalized();
    return n.dot(other) > 0 ? Vec3(-n) : n;
  };
  const Vec3 n12 = outward(e1, e2, e3), n23 = outward(e2, e3, e1), n31 = outward(e3, e1, e2);
  const double angles = std::acos(e1.dot(e2)) + std::acos(e2.dot(e3)) + std::acos(e3.dot(e1));
  const std::vector<CornerEdge> edges = {{e1, n31, n12}, {e2, n12, n23}, {e3, n23, n31}};
  const double r = 0.003;
  const VolumeMoments exact = corner_sector_moments(p, angles, edges, r);

  std::vector<double> x, w;
  const int n = 40;
  gauss_legendre(n, x, w);
  const Vec3 plane_n = (n23 - n12).cross(n31 - n12).normalized();
  const double h = std::abs(plane_n.dot(n12));
  const double area2 = (n23 - n12).cross(n31 - n12).norm();  // twice the flat triangle's area
  VolumeMoments q;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        // Duffy: (s, t) in the unit square -> triangle (1 - s, s (1 - t), s t), Jacobian s.
        const double s = x[i], t = x[j];
        const Vec3 flat = (1.0 - s) * n12 + s * (1.0 - t) * n23 + s * t * n31;
        const Vec3 dir = flat.normalized();
        const double domega = w[i] * w[j] * s * area2 * h / std::pow(flat.norm(), 3);
        const double rho = r * x[k];
        const double dv = domega * w[k] * r * rho * rho;
        const Vec3 pt = p + rho * dir;
        q.volume += dv;
        q.first += dv * pt;
        q.second += dv * pt * pt.transpose();
      }
  expect_moments_near(exact, q, q.volume, 0.005, 1e-11);
}

TEST(RoundedMassProperties, RoundedCubeMatchesSteinerAndAnIndependentDecomposition) {
  const double s = 0.016, r = 0.002, c = s - 2.0 * r;
  const Body b = shaped("shape = \"d6\"\nsize = 0.016\nrounding = 0.002\n");
  EXPECT_EQ(b.shape.rounding, r);
  // Steiner: V = c^3 + 6 c^2 r + 3 pi c r^2 + 4/3 pi r^3 (12 edges of quarter cylinders, angle pi/2).
  const double volume = c * c * c + 6.0 * c * c * r + 3.0 * kPi * c * r * r + 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(b.mass.mass, kDensity * volume, kRel * kDensity * volume);
  EXPECT_NEAR(RoundedSolid(b.shape, r).steiner_volume(), volume, kRel * volume);
  // int x^2 dV over the pieces, axis-aligned (h = c/2):
  //   core c^5/12; the +-x slabs c^2 ((h+r)^3 - h^3)/3 each; the other four slabs c^3/12 c r each;
  //   4 edges along x: c^3/12 pi r^2/4 each; 8 other edges: c (h^2 pi r^2/4 + 2 h r^3/3 + pi r^4/16);
  //   8 corners: h^2 pi r^3/6 + 2 h pi r^4/16 + pi r^5/30.
  const double h = c / 2.0;
  const double xx = std::pow(c, 5) / 12.0 + 2.0 * c * c * (std::pow(h + r, 3) - h * h * h) / 3.0 +
                    4.0 * c * c * c / 12.0 * c * r + 4.0 * c * c * c / 12.0 * kPi * r * r / 4.0 +
                    8.0 * c * (h * h * kPi * r * r / 4.0 + 2.0 * h * r * r * r / 3.0 + kPi * std::pow(r, 4) / 16.0) +
                    8.0 * (h * h * kPi * r * r * r / 6.0 + 2.0 * h * kPi * std::pow(r, 4) / 16.0 + kPi * std::pow(r, 5) / 30.0);
  expect_isotropic(b.mass, kDensity * 2.0 * xx, kDensity * volume);
}

TEST(RoundedMassProperties, RoundedPresetsKeepTheirSymmetryAndSteinerVolume) {
  for (const char* shape : {"d4", "d8", "d12", "d20"}) {
    SCOPED_TRACE(shape);
    const Body sharp = shaped(std::string("shape = \"") + shape + "\"\nsize = 0.02\n");
    const Body b = shaped(std::string("shape = \"") + shape + "\"\nsize = 0.02\nrounding = 0.001\n");
    EXPECT_EQ(b.shape.faces.size(), sharp.shape.faces.size());
    EXPECT_LT(b.mass.mass, sharp.mass.mass);
    EXPECT_NEAR(b.mass.mass, kDensity * RoundedSolid(b.shape, 0.001).steiner_volume(), kRel * b.mass.mass);
    expect_isotropic(b.mass, b.mass.inertia.trace() / 3.0, b.mass.mass);
    // The flat faces stay where they were: same face planes.
    for (std::size_t f = 0; f < b.shape.faces.size(); ++f) {
      const Vec3& n = b.shape.normals[f];
      const int g = nearest_face(sharp.shape, n);
      EXPECT_NEAR(n.dot(b.shape.vertices[b.shape.faces[f][0]]) + 0.001,
                  n.dot(sharp.shape.vertices[sharp.shape.faces[g][0]]), 1e-15);
    }
  }
}

TEST(RoundedMassProperties, ABallIsTheLimitOfATinyCore) {
  // Core a cube of edge 1e-9: the rounded die is a ball of radius r to first order.
  const double r = 0.005;
  const Body b = shaped("shape = \"d6\"\nsize = 0.010000001\nrounding = 0.005\n");
  const double volume = 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(b.mass.mass, kDensity * volume, 1e-6 * kDensity * volume);
  expect_matrix_near(b.mass.inertia, 0.4 * b.mass.mass * r * r * Mat3::Identity(), 1e-6 * b.mass.inertia.trace());
}

TEST(LoadedMassProperties, RegionOnAPresetIsExact) {
  // A d8 whose z <= 0 half is steel: mass of each half = V/2 rho; the COM moves down by
  // (rho_s - rho_p) / (rho_s + rho_p) times the half's centroid height (3/8 of the apex height a/sqrt2... for
  // a square pyramid of height H the centroid is H/4 above the base).
  const Body b = shaped("shape = \"d8\"\nsize = 0.02\n[[die.regions]]\nmaterial = \"steel\"\ncuts = [{normal = [0, 0, 1]}]\n",
                        "[materials.steel]\ndensity = 7800.0\n");
  const double a = 0.01 * std::sqrt(6.0) / 2.0 * std::sqrt(2.0) / 2.0 * 2.0;  // vertex distance: inradius sqrt3
  const double H = 0.01 * std::sqrt(3.0);                                     // apex height above the equator
  (void)a;
  const double volume = 4.0 / 3.0 * H * H * H;  // two square pyramids of base (H sqrt2)^2 and height H
  EXPECT_NEAR(b.mass.mass, (kDensity + 7800.0) / 2.0 * volume, kRel * b.mass.mass);
  EXPECT_NEAR(b.mass.com.z(), (kDensity - 7800.0) / (kDensity + 7800.0) * H / 4.0, 1e-15);
}

}  // namespace
}  // namespace dicesim

namespace dicesim {
namespace {

TEST(RoundedMassProperties, SlabCutOfARoundedCubeIsExact) {
  // A rounded d6 (core edge c = s - 2r, h = c/2) whose z <= 0 half is lead. The cut is
  // perpendicular to the four vertical edges (split exactly along their length) and misses every
  // other rounded piece. By symmetry each half has volume V/2; the first moment of the upper half:
  //   core c^2 h^2/2; top slab c^2 ((h+r)^2 - h^2)/2; 4 side slabs c r h^2/2;
  //   4 top edges c (h pi r^2/4 + r^3/3); 4 vertical half-edges pi r^2/4 h^2/2;
  //   4 top corners h pi r^3/6 + pi r^4/16.
  const double s = 0.016, r = 0.002, c = s - 2.0 * r, h = c / 2.0, lead = 11340.0;
  const Body b = shaped("shape = \"d6\"\nsize = 0.016\nrounding = 0.002\n[[die.regions]]\nmaterial = \"lead\"\n"
                        "cuts = [{normal = [0, 0, 1]}]\n",
                        "[materials.lead]\ndensity = 11340.0\n");
  const double volume = c * c * c + 6.0 * c * c * r + 3.0 * kPi * c * r * r + 4.0 / 3.0 * kPi * r * r * r;
  const double zup = c * c * h * h / 2.0 + c * c * ((h + r) * (h + r) - h * h) / 2.0 + 4.0 * c * r * h * h / 2.0 +
                     4.0 * c * (h * kPi * r * r / 4.0 + r * r * r / 3.0) + 4.0 * kPi * r * r / 4.0 * h * h / 2.0 +
                     4.0 * (h * kPi * r * r * r / 6.0 + kPi * std::pow(r, 4) / 16.0);
  const double mass = (kDensity + lead) / 2.0 * volume;
  EXPECT_NEAR(b.mass.mass, mass, kRel * mass);
  EXPECT_NEAR(b.mass.com.z(), (kDensity - lead) * zup / mass, 1e-12 * h);
  EXPECT_LE(b.mass.com.head<2>().norm(), 1e-15);
}

}  // namespace
}  // namespace dicesim

// The contact patch of two touching convex polytopes (sim/dynamics/contact_patch.hpp): boxes and
// cubes placed by hand so that the overlap of their features is known exactly. A face on a face
// gives the overlap's corners (a's corners, b's, and crossings of their edges), cut to four that
// span it when there are more; an edge across a narrow face the two points where it leaves the
// face; crossed edges their crossing; a corner on a face the corner; a half-space a's lowest face;
// rounded corners the same points on the plane midway between the surfaces; features side by side
// nothing. The overlaps of random faces are checked against an independent clipping of one square
// by the other.
#include "sim/dynamics/contact_patch.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace dicesim {
namespace {

constexpr double kSlab = 1e-9;
constexpr double kTol = 1e-12;  // the sizes here are ~1: relative and absolute alike

// The 8 corners of a box of half-extents `half`, turned by R about its centre, in the world.
std::vector<Vec3> box(const Vec3& centre, const Vec3& half, const Mat3& R = Mat3::Identity()) {
  std::vector<Vec3> out;
  for (int i = 0; i < 8; ++i)
    out.push_back(centre + R * Vec3(i & 1 ? half.x() : -half.x(), i & 2 ? half.y() : -half.y(),
                                    i & 4 ? half.z() : -half.z()));
  return out;
}

// The same corners moved along z so that the lowest is at height `z` exactly (for the lowest).
std::vector<Vec3> lowest_at(std::vector<Vec3> c, double z) {
  double lo = c[0].z();
  for (const Vec3& p : c) lo = std::min(lo, p.z());
  for (Vec3& p : c) p.z() += z - lo;
  return c;
}
std::vector<Vec3> highest_at(std::vector<Vec3> c, double z) {
  double hi = c[0].z();
  for (const Vec3& p : c) hi = std::max(hi, p.z());
  for (Vec3& p : c) p.z() += z - hi;
  return c;
}

Mat3 about(const Vec3& axis, double angle) { return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix(); }

// Turns a cube's corner (-1, -1, -1) / 2 straight down (its body diagonal vertical).
Mat3 corner_down() {
  const Vec3 from = Vec3(-1, -1, -1).normalized(), to = -Vec3::UnitZ();
  return about(from.cross(to), std::acos(from.dot(to)));
}

std::string show(const ContactPatch& p) {
  std::string s;
  char buf[128];
  for (int i = 0; i < p.n; ++i) {
    const Vec3& x = p.points[static_cast<std::size_t>(i)];
    std::snprintf(buf, sizeof buf, " (%.17g, %.17g, %.17g)", x.x(), x.y(), x.z());
    s += buf;
  }
  return "n=" + std::to_string(p.n) + ":" + s;
}

// The patch's points are exactly `expected`, in any order (each within tol of one, one to one).
void expect_points(const ContactPatch& p, const std::vector<Vec3>& expected, double tol = kTol) {
  ASSERT_EQ(p.n, static_cast<int>(expected.size())) << show(p);
  std::vector<bool> used(expected.size(), false);
  for (int i = 0; i < p.n; ++i) {
    const Vec3& x = p.points[static_cast<std::size_t>(i)];
    bool found = false;
    for (std::size_t k = 0; k < expected.size() && !found; ++k)
      if (!used[k] && (x - expected[k]).norm() <= tol * std::max(1.0, expected[k].norm())) used[k] = found = true;
    EXPECT_TRUE(found) << "point " << i << " (" << x.transpose() << ") is none of the expected; " << show(p);
  }
}

ContactPatch patch_on(const std::vector<Vec3>& a, const std::vector<Vec3>& b, double level_a = 0.0,
                      double level_b = 0.0, double rounding_a = 0.0, double rounding_b = 0.0,
                      const Vec3& n = Vec3::UnitZ()) {
  return contact_patch({a, rounding_a}, {b, rounding_b}, n, level_a, level_b, kSlab);
}

// ---------------------------------------------------------------------------------------------
// An independent overlap of two convex polygons in the xy-plane: Sutherland-Hodgman clipping of
// one by the other's edges (counter-clockwise), near-duplicate corners merged.

using Poly = std::vector<Eigen::Vector2d>;

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

Poly clip(const Poly& subject, const Poly& clipper) {
  Poly out = subject;
  for (std::size_t i = 0; i < clipper.size() && !out.empty(); ++i) {
    const Eigen::Vector2d a = clipper[i], e = clipper[(i + 1) % clipper.size()] - a;
    const Poly in = out;
    out.clear();
    for (std::size_t k = 0; k < in.size(); ++k) {
      const Eigen::Vector2d p = in[k], q = in[(k + 1) % in.size()];
      const double sp = cross2(e, p - a), sq = cross2(e, q - a);
      if (sp >= 0.0) out.push_back(p);
      if ((sp >= 0.0) != (sq >= 0.0)) out.push_back(p + sp / (sp - sq) * (q - p));
    }
  }
  Poly merged;
  for (const auto& p : out)
    if (merged.empty() || (p - merged.back()).norm() > 1e-9) merged.push_back(p);
  while (merged.size() > 1 && (merged.front() - merged.back()).norm() <= 1e-9) merged.pop_back();
  // Drop corners on a straight run (a clipping line through a subject's corner).
  Poly corners;
  for (std::size_t k = 0; k < merged.size(); ++k) {
    const auto& prev = merged[(k + merged.size() - 1) % merged.size()];
    const auto& next = merged[(k + 1) % merged.size()];
    if (merged.size() < 3 || std::abs(cross2(merged[k] - prev, next - merged[k])) > 1e-12) corners.push_back(merged[k]);
  }
  return corners;
}

// Area of the convex hull of points (ordered about their centroid).
double hull_area(std::vector<Eigen::Vector2d> pts) {
  if (pts.size() < 3) return 0.0;
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : pts) c += p / static_cast<double>(pts.size());
  std::sort(pts.begin(), pts.end(), [&](const auto& a, const auto& b) {
    return std::atan2(a.y() - c.y(), a.x() - c.x()) < std::atan2(b.y() - c.y(), b.x() - c.x());
  });
  double area = 0.0;
  for (std::size_t k = 0; k < pts.size(); ++k) area += cross2(pts[k], pts[(k + 1) % pts.size()]);
  return 0.5 * area;
}

// The bottom face (a) or top face (b) of a box as a counter-clockwise polygon in xy.
Poly square_xy(const Vec3& centre, double hx, double hy, double yaw) {
  const Eigen::Rotation2Dd r(yaw);
  Poly p;
  for (const auto& [x, y] : {std::pair{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}})
    p.push_back(Eigen::Vector2d(centre.x(), centre.y()) + r * Eigen::Vector2d(x, y));
  return p;
}

// The patch of a face on a face with more than four overlap corners: at most four, all corners of
// the overlap (no other points), spanning at least half of it; with four or fewer, all of them.
void expect_spanning_corners(const ContactPatch& p, const Poly& overlap, double z, const std::string& what) {
  SCOPED_TRACE(what);
  for (int i = 0; i < p.n; ++i) EXPECT_NEAR(p.points[static_cast<std::size_t>(i)].z(), z, kTol);
  if (overlap.size() <= 4) {
    std::vector<Vec3> expected;
    for (const auto& q : overlap) expected.emplace_back(q.x(), q.y(), z);
    expect_points(p, expected, 1e-9);
    return;
  }
  ASSERT_LE(p.n, 4) << show(p);
  ASSERT_GE(p.n, 3) << show(p);
  std::vector<Eigen::Vector2d> kept;
  for (int i = 0; i < p.n; ++i) {
    const Vec3& x = p.points[static_cast<std::size_t>(i)];
    const Eigen::Vector2d q(x.x(), x.y());
    double nearest = 1e300;
    for (const auto& c : overlap) nearest = std::min(nearest, (c - q).norm());
    EXPECT_LE(nearest, 1e-9) << "point " << i << " is not a corner of the overlap; " << show(p);
    kept.push_back(q);
  }
  EXPECT_GE(hull_area(kept), 0.5 * hull_area(overlap)) << show(p);
}

// ---------------------------------------------------------------------------------------------

// A unit cube wholly on a bigger box's top face: its four bottom corners.
TEST(ContactPatch, FaceOnBiggerFaceGivesTheSmallerFacesCorners) {
  const auto b = box({0, 0, -0.5}, {2, 2, 0.5});
  const auto a = box({0.25, -0.5, 0.5}, {0.5, 0.5, 0.5});
  expect_points(patch_on(a, b), {{-0.25, -1, 0}, {0.75, -1, 0}, {0.75, 0, 0}, {-0.25, 0, 0}});
  // Either way round (b's top face wholly inside a's bottom face).
  const auto a2 = box({0, 0, 0.5}, {2, 2, 0.5});
  const auto b2 = box({0.25, -0.5, -0.5}, {0.5, 0.5, 0.5});
  expect_points(patch_on(a2, b2), {{-0.25, -1, 0}, {0.75, -1, 0}, {0.75, 0, 0}, {-0.25, 0, 0}});
}

// Offset so the faces overlap in part: one corner is a's, one b's, two are crossings of their edges.
TEST(ContactPatch, FaceOnFaceOffsetGivesTheOverlapRectanglesCorners) {
  const auto b = box({0, 0, -0.5}, {1, 0.75, 0.5});  // top face x in [-1, 1], y in [-0.75, 0.75]
  const auto a = box({0.75, 0.5, 0.5}, {0.5, 0.5, 0.5});  // bottom face x in [0.25, 1.25], y in [0, 1]
  expect_points(patch_on(a, b), {
                                    {0.25, 0.0, 0.0},   // a's corner
                                    {1.0, 0.75, 0.0},   // b's corner
                                    {1.0, 0.0, 0.0},    // a's edge y = 0 across b's x = 1
                                    {0.25, 0.75, 0.0},  // a's edge x = 0.25 across b's y = 0.75
                                });
}

// A cube turned 45 degrees about the normal on an equal cube: the overlap is a regular octagon of
// edge crossings only (corners of neither body); four of them that span it are kept.
TEST(ContactPatch, FaceOnFaceTurned45GivesFourCornersOfTheOctagon) {
  const double h = std::sqrt(0.5), k = h - 0.5;  // the diamond's half-diagonal; the octagon's short offset
  const auto b = box({0, 0, -0.5}, {0.5, 0.5, 0.5});
  const auto a = box({0, 0, 0.5}, {0.5, 0.5, 0.5}, about(Vec3::UnitZ(), kPi / 4));
  const Poly octagon{{0.5, -k}, {0.5, k}, {k, 0.5}, {-k, 0.5}, {-0.5, k}, {-0.5, -k}, {-k, -0.5}, {k, -0.5}};
  EXPECT_EQ(clip(square_xy({0, 0, 0}, 0.5, 0.5, kPi / 4), square_xy({0, 0, 0}, 0.5, 0.5, 0.0)).size(), 8u);
  const ContactPatch p = patch_on(a, b);
  EXPECT_EQ(p.n, 4) << show(p);
  expect_spanning_corners(p, octagon, 0.0, "octagon");
  // None of them is a corner of either body.
  for (int i = 0; i < p.n; ++i)
    for (const auto* body : {&a, &b})
      for (const Vec3& c : *body)
        EXPECT_GT((p.points[static_cast<std::size_t>(i)] - c).norm(), 1e-3) << show(p);
}

// Turned by 30 degrees and offset: the overlap mixes b's corner, a's corners and crossings.
TEST(ContactPatch, FaceOnFaceTurnedAndOffsetKeepsSpanningCornersOfTheOverlap) {
  const double yaw = kPi / 6;
  const Vec3 ca(0.55, 0.3, 0.5);
  const auto b = box({0, 0, -0.5}, {0.6, 0.5, 0.5});
  const auto a = box(ca, {0.5, 0.5, 0.5}, about(Vec3::UnitZ(), yaw));
  const Poly overlap = clip(square_xy(ca, 0.5, 0.5, yaw), square_xy({0, 0, 0}, 0.6, 0.5, 0.0));
  ASSERT_GT(overlap.size(), 4u);
  expect_spanning_corners(patch_on(a, b), overlap, 0.0, "turned 30, offset");
}

// Random faces on faces (sizes, turns about the normal, offsets), against the clipping.
TEST(ContactPatch, RandomFaceOnFaceKeepsSpanningCornersOfTheOverlap) {
  std::mt19937_64 rng(0x5eed'c0de'2024ULL);
  std::uniform_real_distribution<double> u(-1.0, 1.0), size(0.2, 1.0);
  int more_than_four = 0, tested = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double hax = size(rng), hay = size(rng), hbx = size(rng), hby = size(rng);
    const double yaw_a = kPi * u(rng), yaw_b = kPi * u(rng);
    const Vec3 ca(u(rng), u(rng), hax), cb(0.3 * u(rng), 0.3 * u(rng), -0.5);
    const auto a = box(ca, {hax, hay, hax}, about(Vec3::UnitZ(), yaw_a));
    const auto b = box(cb, {hbx, hby, 0.5}, about(Vec3::UnitZ(), yaw_b));
    const Poly overlap = clip(square_xy(ca, hax, hay, yaw_a), square_xy(cb, hbx, hby, yaw_b));
    const ContactPatch p = patch_on(a, b);
    if (overlap.size() < 3 || hull_area(overlap) < 1e-6) continue;  // slivers: near-ties decide
    ++tested;
    more_than_four += overlap.size() > 4;
    expect_spanning_corners(p, overlap, 0.0, "trial " + std::to_string(trial));
  }
  EXPECT_GT(tested, 200);
  EXPECT_GT(more_than_four, 50);
}

// The whole offset scene turned by a rotation (a normal along no axis): the points turn with it.
TEST(ContactPatch, TiltedNormalGivesTheTurnedPoints) {
  const Mat3 Q = about(Vec3(1, -2, 0.5), 0.9);
  auto turned = [&](std::vector<Vec3> c) {
    for (Vec3& p : c) p = Q * p;
    return c;
  };
  const auto b = turned(box({0, 0, -0.5}, {1, 0.75, 0.5}));
  const auto a = turned(box({0.75, 0.5, 0.5}, {0.5, 0.5, 0.5}));
  const Vec3 n = Q * Vec3::UnitZ();
  expect_points(patch_on(a, b, 0.0, 0.0, 0.0, 0.0, n),
                {Q * Vec3(0.25, 0, 0), Q * Vec3(1, 0.75, 0), Q * Vec3(1, 0, 0), Q * Vec3(0.25, 0.75, 0)}, 1e-11);
}

// A cube turned 45 degrees about x rests on its lower edge (along x, length 1) across a box's top
// face 0.5 wide in x: it touches where the edge leaves the face, corners of neither body.
TEST(ContactPatch, EdgeAcrossNarrowFaceGivesTheTwoPointsWhereItLeaves) {
  const auto b = box({0, 0, -0.5}, {0.25, 1, 0.5});
  const auto a = lowest_at(box({0, 0.1, 1}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), kPi / 4)), 0.0);
  const ContactPatch p = patch_on(a, b);
  expect_points(p, {{-0.25, 0.1, 0}, {0.25, 0.1, 0}});
  // Swapped roles: the narrow box's bottom face on the cube's upper edge.
  const auto a2 = box({0, 0, 0.5}, {0.25, 1, 0.5});
  const auto b2 = highest_at(box({0, 0.1, -1}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), kPi / 4)), 0.0);
  expect_points(patch_on(a2, b2), {{-0.25, 0.1, 0}, {0.25, 0.1, 0}});
}

// An edge shorter than the face across it: its two ends (a's corners).
TEST(ContactPatch, EdgeWithinFaceGivesItsEnds) {
  const auto b = box({0, 0, -0.5}, {2, 2, 0.5});
  const auto a = lowest_at(box({0.3, 0.1, 1}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), kPi / 4)), 0.0);
  expect_points(patch_on(a, b), {{-0.2, 0.1, 0}, {0.8, 0.1, 0}});
}

// a's lower edge along x over b's upper edge along y: the crossing, a corner of neither.
TEST(ContactPatch, EdgeAcrossEdgeGivesTheCrossing) {
  const auto a = lowest_at(box({0.1, 0.2, 1}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), kPi / 4)), 0.0);
  const auto b = highest_at(box({-0.15, 0.05, -1}, {0.5, 0.5, 0.5}, about(Vec3::UnitY(), kPi / 4)), 0.0);
  // a's edge: y = 0.2, x in [-0.4, 0.6]; b's: x = -0.15, y in [-0.45, 0.55].
  expect_points(patch_on(a, b), {{-0.15, 0.2, 0}});
  // Crossed at 60 degrees instead (b turned about z as well): still the one crossing.
  const Mat3 R = about(Vec3::UnitZ(), kPi / 6) * about(Vec3::UnitY(), kPi / 4);
  const auto b2 = highest_at(box({-0.15, 0.2, -1}, {0.5, 0.5, 0.5}, R), 0.0);
  expect_points(patch_on(a, b2), {{-0.15, 0.2, 0}});
}

// A cube standing on a corner (its body diagonal vertical) on a face: that corner.
TEST(ContactPatch, CornerOnFaceGivesTheCorner) {
  const Mat3 R = corner_down();
  const auto a = lowest_at(box({0.3, -0.2, 2}, {0.5, 0.5, 0.5}, R), 0.0);
  const Vec3 tip = *std::min_element(a.begin(), a.end(), [](const Vec3& p, const Vec3& q) { return p.z() < q.z(); });
  EXPECT_NEAR(tip.x(), 0.3, 1e-12);
  EXPECT_NEAR(tip.y(), -0.2, 1e-12);
  const auto b = box({0, 0, -0.5}, {1, 1, 0.5});
  expect_points(patch_on(a, b), {{tip.x(), tip.y(), 0}});
  // And a face (b, below) on a's corner, a a half-space's worth of face above: b's corner up.
  const auto b2 = highest_at(box({0.3, -0.2, -2}, {0.5, 0.5, 0.5}, R), 0.0);
  const auto a2 = box({0, 0, 0.5}, {1, 1, 0.5});
  const Vec3 top = *std::max_element(b2.begin(), b2.end(), [](const Vec3& p, const Vec3& q) { return p.z() < q.z(); });
  expect_points(patch_on(a2, b2), {{top.x(), top.y(), 0}});
}

// b a half-space (no corners): a's feature whole. A cube flat: its bottom face's corners; resting
// on an edge: the edge's ends; on a corner: the corner.
TEST(ContactPatch, HalfSpaceGivesTheLowestFeaturesCorners) {
  const std::vector<Vec3> none;
  const auto flat = box({0.5, 0.25, 0.5}, {0.5, 0.5, 0.5});
  expect_points(patch_on(flat, none), {{0, -0.25, 0}, {1, -0.25, 0}, {1, 0.75, 0}, {0, 0.75, 0}});
  const auto edge = lowest_at(box({0.3, 0.1, 1}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), kPi / 4)), 0.0);
  expect_points(patch_on(edge, none), {{-0.2, 0.1, 0}, {0.8, 0.1, 0}});
  const Mat3 R = corner_down();
  const auto corner = lowest_at(box({0.3, -0.2, 2}, {0.5, 0.5, 0.5}, R), 0.0);
  const ContactPatch p = patch_on(corner, none);
  ASSERT_EQ(p.n, 1) << show(p);
  EXPECT_NEAR(p.points[0].x(), 0.3, 1e-12);
  EXPECT_NEAR(p.points[0].y(), -0.2, 1e-12);
  EXPECT_NEAR(p.points[0].z(), 0.0, 1e-15);
  // A cube a little tilted, its corners lifted by less than the slab: still its bottom face; tilted
  // more, only the edge that stays within the slab.
  const auto tilted = lowest_at(box({0.5, 0.25, 0.5}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), 1e-10)), 0.0);
  EXPECT_EQ(patch_on(tilted, none).n, 4);
  const auto more = lowest_at(box({0.5, 0.25, 0.5}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), 1e-6)), 0.0);
  EXPECT_EQ(patch_on(more, none).n, 2) << show(patch_on(more, none));
}

// Rounded corners (radius r, the corners' centres given): the same cube lifted by 2 r rests with its
// rounded surface on b's, both surfaces at z = r; the patch is the unrounded one's, at z = r. With a
// gap g between the surfaces, on the plane midway.
TEST(ContactPatch, RoundedCornersGiveTheSamePointsOnTheMidPlane) {
  const double r = 0.05;
  const auto b = box({0, 0, -0.5}, {1, 0.75, 0.5});
  const auto a = box({0.75, 0.5, 0.5 + 2 * r}, {0.5, 0.5, 0.5});
  const std::vector<Vec3> xy{{0.25, 0, 0}, {1, 0.75, 0}, {1, 0, 0}, {0.25, 0.75, 0}};
  auto at = [&](double z) {
    std::vector<Vec3> out = xy;
    for (Vec3& p : out) p.z() = z;
    return out;
  };
  expect_points(patch_on(a, b, r, r, r, r), at(r));
  const double g = 0.01;  // a's surface at r + g, b's at r
  const auto a_up = box({0.75, 0.5, 0.5 + 2 * r + g}, {0.5, 0.5, 0.5});
  expect_points(patch_on(a_up, b, r + g, r, r, r), at(r + 0.5 * g));
  // Only a rounded, against a sharp b (surface at 0): a's centres at r.
  const auto a_only = box({0.75, 0.5, 0.5 + r}, {0.5, 0.5, 0.5});
  expect_points(patch_on(a_only, b, 0.0, 0.0, r, 0.0), at(0.0));
  // A rounded cube on its edge across the narrow face, and on a half-space.
  const auto narrow = box({0, 0, -0.5}, {0.25, 1, 0.5});
  const auto edge = lowest_at(box({0, 0.1, 1}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), kPi / 4)), 2 * r);
  expect_points(patch_on(edge, narrow, r, r, r, r), {{-0.25, 0.1, r}, {0.25, 0.1, r}});
  expect_points(patch_on(a, {}, r, r, r, 0.0), {{0.25, 0, r}, {1.25, 0, r}, {1.25, 1, r}, {0.25, 1, r}});
}

// Features side by side across the normal: nothing.
TEST(ContactPatch, SideBySideFeaturesGiveNoPoints) {
  const auto b = box({0, 0, -0.5}, {1, 1, 0.5});
  // A face beside the face (a gap of 0.5 in x).
  EXPECT_EQ(patch_on(box({2, 0, 0.5}, {0.5, 0.5, 0.5}), b).n, 0);
  // An edge along x beyond the face's end, and one along y beside it.
  const auto edge_x = lowest_at(box({2, 0, 1}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), kPi / 4)), 0.0);
  EXPECT_EQ(patch_on(edge_x, b).n, 0) << show(patch_on(edge_x, b));
  const auto edge_y = lowest_at(box({1.5, 0, 1}, {0.5, 0.5, 0.5}, about(Vec3::UnitY(), kPi / 4)), 0.0);
  EXPECT_EQ(patch_on(edge_y, b).n, 0) << show(patch_on(edge_y, b));
  // Crossed edges whose shadows miss each other.
  const auto ea = lowest_at(box({0, 0.2, 1}, {0.5, 0.5, 0.5}, about(Vec3::UnitX(), kPi / 4)), 0.0);
  const auto eb = highest_at(box({0.8, 0, -1}, {0.5, 0.5, 0.5}, about(Vec3::UnitY(), kPi / 4)), 0.0);
  EXPECT_EQ(patch_on(ea, eb).n, 0) << show(patch_on(ea, eb));
  // A corner beside the face.
  const Mat3 R = corner_down();
  const auto corner = lowest_at(box({1.1, 0.3, 2}, {0.5, 0.5, 0.5}, R), 0.0);
  EXPECT_EQ(patch_on(corner, b).n, 0) << show(patch_on(corner, b));
}

// A side whose corners are all farther than the slab from its plane has no feature, so there is no
// patch (an empty polygon once counted as containing every point: the other side's whole feature
// came back, as if it lay on a half-space).
TEST(ContactPatch, EmptyFeatureGivesNoPoints) {
  const auto a = box({0.5, 0.25, 0.5}, {0.5, 0.5, 0.5});       // bottom face at z = 0
  const auto b = box({0, 0, -0.5 - 1e-6}, {1, 1, 0.5});          // top face at z = -1e-6, beyond the slab
  EXPECT_EQ(patch_on(a, b, 0.0, 0.0).n, 0) << show(patch_on(a, b, 0.0, 0.0));
  EXPECT_EQ(patch_on(b, a, 0.0, 0.0, 0.0, 0.0, -Vec3::UnitZ()).n, 0)
      << show(patch_on(b, a, 0.0, 0.0, 0.0, 0.0, -Vec3::UnitZ()));
}

// The regular n-gon prism of circumradius 1 between heights z0 and z1, turned by `turn` about z.
std::vector<Vec3> prism(int sides, double turn, double z0, double z1) {
  std::vector<Vec3> out;
  for (int k = 0; k < sides; ++k) {
    const double t = 2 * kPi * (k + 0.5) / sides + turn;
    out.emplace_back(std::cos(t), std::sin(t), z0);
    out.emplace_back(std::cos(t), std::sin(t), z1);
  }
  return out;
}
Poly ngon(int sides, double turn) {
  Poly p;
  for (int k = 0; k < sides; ++k) {
    const double t = 2 * kPi * (k + 0.5) / sides + turn;
    p.emplace_back(std::cos(t), std::sin(t));
  }
  return p;
}

// Faces of many corners: at most four points, spanning at least half the overlap, about its middle.
// (Once: a half-space's patch was not reduced, points past 16 were dropped before the reduction in
// the order found, and a feature was cut to its first 32 corners: a 20-gon on a 20-gon turned by
// half a step kept 3 points spanning 18 % of the overlap.)
TEST(ContactPatch, ManyCornersGiveFourSpanningPoints) {
  auto check = [](const ContactPatch& p, const Poly& overlap, const std::string& what) {
    SCOPED_TRACE(what);
    EXPECT_LE(p.n, 4) << show(p);
    Vec3 centroid = Vec3::Zero();
    std::vector<Eigen::Vector2d> kept;
    for (int i = 0; i < p.n; ++i) {
      const Vec3& x = p.points[static_cast<std::size_t>(i)];
      centroid += x / p.n;
      kept.emplace_back(x.x(), x.y());
    }
    EXPECT_LT(centroid.norm(), 0.25) << "the points lie to one side; " << show(p);
    EXPECT_GE(hull_area(kept), 0.5 * hull_area(overlap)) << show(p);
  };
  const std::vector<Vec3> none;
  for (const int sides : {6, 20, 40}) {
    check(patch_on(prism(sides, 0.0, 0.0, 1.0), none), ngon(sides, 0.0), std::to_string(sides) + "-gon on a half-space");
    check(patch_on(prism(sides, 0.0, 0.0, 1.0), box({0, 0, -0.5}, {2, 2, 0.5})), ngon(sides, 0.0),
          std::to_string(sides) + "-gon on a bigger box");
    check(patch_on(prism(sides, kPi / sides, 0.0, 1.0), prism(sides, 0.0, -1.0, 0.0)),
          clip(ngon(sides, kPi / sides), ngon(sides, 0.0)), std::to_string(sides) + "-gon on a turned one");
  }
}

}  // namespace
}  // namespace dicesim

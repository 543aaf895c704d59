// Tests for the convex narrow phase (sim/dynamics/convex_distance.hpp): cubes at known separations
// (face-face, crossed edges, corner-face), overlaps of known depth, a tetrahedron against a cube,
// distances from points, and random pairs against two independent checks: an exact feature-pair
// reference (every corner against every face, every edge against every edge) and the
// separating-plane certificate; overlaps against sampled directions and the translation that should
// just separate them.
#include "sim/dynamics/convex_distance.hpp"
#include "tests/random_geometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

namespace dicesim {
namespace {

// ---------------------------------------------------------------------------------------------
// Hulls built by brute force (every plane through three points with all points on one side), so
// the reference shares no code with the narrow phase.

struct Hull {
  std::vector<Vec3> corners, normals, edges;
  std::vector<std::array<int, 3>> tris;  // counter-clockwise from outside; coplanar faces fan out
  PlacedHull placed(const Mat3& R, const Vec3& x) const { return {corners, normals, edges, R, x}; }
};

Hull hull_of(const std::vector<Vec3>& pts) {
  Hull h;
  h.corners = pts;
  double scale = 0.0;
  for (const Vec3& p : pts) scale = std::max(scale, p.norm());
  const double eps = 1e-10 * scale;
  const int n = static_cast<int>(pts.size());
  auto add_unique = [](std::vector<Vec3>& list, const Vec3& u, bool either_sign) {
    for (const Vec3& e : list)
      if (e.dot(u) > 1.0 - 1e-12 || (either_sign && e.dot(u) < -1.0 + 1e-12)) return;
    list.push_back(u);
  };
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k) {
        Vec3 nrm = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
        if (nrm.norm() < 1e-9 * scale * scale) continue;
        nrm.normalize();
        bool pos = false, neg = false;
        for (int m = 0; m < n; ++m) {
          const double d = nrm.dot(pts[m] - pts[i]);
          pos |= d > eps;
          neg |= d < -eps;
        }
        if (pos && neg) continue;
        std::array<int, 3> t{i, j, k};
        if (pos) {
          nrm = -nrm;
          std::swap(t[1], t[2]);
        }
        h.tris.push_back(t);
        add_unique(h.normals, nrm, false);
        for (int e = 0; e < 3; ++e) add_unique(h.edges, (pts[t[(e + 1) % 3]] - pts[t[e]]).normalized(), true);
      }
  return h;
}

// A cube of side `side` about its centre, with the minimal axes a caller would pass: six face
// normals, one edge direction per parallel class.
Hull cube(double side = 1.0) {
  std::vector<Vec3> pts;
  for (int i = 0; i < 8; ++i)
    pts.push_back(0.5 * side * Vec3(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0));
  Hull h = hull_of(pts);
  h.normals = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  h.edges = {Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  return h;
}

// A regular tetrahedron with corners s (1,1,1), s (1,-1,-1), s (-1,1,-1), s (-1,-1,1).
Hull tetrahedron(double s) {
  return hull_of({s * Vec3(1, 1, 1), s * Vec3(1, -1, -1), s * Vec3(-1, 1, -1), s * Vec3(-1, -1, 1)});
}

Mat3 rot_y(double a) { return Eigen::AngleAxisd(a, Vec3::UnitY()).toRotationMatrix(); }
Mat3 turn(const Vec3& from, const Vec3& to) {
  return Eigen::Quaterniond::FromTwoVectors(from, to).toRotationMatrix();
}

using testing::random_rotation;
using testing::random_unit;

std::vector<Vec3> world_corners(const PlacedHull& h) {
  std::vector<Vec3> out;
  for (const Vec3& c : h.corners) out.push_back(h.R * c + h.x);
  return out;
}

// min_B u.b - max_A u.a: > 0 exactly when the plane normal to u separates them; never more than
// their distance.
double support_gap(const PlacedHull& a, const PlacedHull& b, const Vec3& u) {
  double amax = -std::numeric_limits<double>::infinity(), bmin = -amax;
  for (const Vec3& c : world_corners(a)) amax = std::max(amax, u.dot(c));
  for (const Vec3& c : world_corners(b)) bmin = std::min(bmin, u.dot(c));
  return bmin - amax;
}

// ---------------------------------------------------------------------------------------------
// The exact reference for separated polytopes: the nearest pair of features is a corner and a
// face or two edges (Ericson, Real-Time Collision Detection, 5.1.5 and 5.1.9).

Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

double segment_distance(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r);
  const double c = d1.dot(r), b = d1.dot(d2), denom = a * e - b * b;
  double s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0) {
    t = 0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1) {
    t = 1;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  return (p1 + s * d1 - (p2 + t * d2)).norm();
}

double reference_distance(const Hull& ha, const PlacedHull& a, const Hull& hb, const PlacedHull& b) {
  const std::vector<Vec3> ca = world_corners(a), cb = world_corners(b);
  double best = std::numeric_limits<double>::infinity();
  auto corners_vs_faces = [&](const std::vector<Vec3>& pts, const std::vector<Vec3>& c, const Hull& h) {
    for (const Vec3& p : pts)
      for (const auto& t : h.tris) best = std::min(best, (p - closest_on_triangle(p, c[t[0]], c[t[1]], c[t[2]])).norm());
  };
  corners_vs_faces(ca, cb, hb);
  corners_vs_faces(cb, ca, ha);
  for (const auto& s : ha.tris)
    for (int i = 0; i < 3; ++i)
      for (const auto& t : hb.tris)
        for (int j = 0; j < 3; ++j)
          best = std::min(best, segment_distance(ca[s[i]], ca[s[(i + 1) % 3]], cb[t[j]], cb[t[(j + 1) % 3]]));
  return best;
}

// Largest signed distance of p beyond the hull's face planes (<= 0: inside or on).
double beyond_faces(const Hull& h, const PlacedHull& ph, const Vec3& p) {
  const std::vector<Vec3> c = world_corners(ph);
  double worst = -std::numeric_limits<double>::infinity();
  for (const auto& t : h.tris) {
    const Vec3 n = (c[t[1]] - c[t[0]]).cross(c[t[2]] - c[t[0]]).normalized();
    worst = std::max(worst, n.dot(p - c[t[0]]));
  }
  return worst;
}

// Everything a separated answer promises, against the reference. tol: absolute, of the sizes.
void expect_separated(const Hull& ha, const PlacedHull& a, const Hull& hb, const PlacedHull& b, const Separation& s,
                      double tol) {
  ASSERT_GT(s.distance, 0.0);
  EXPECT_FALSE(s.sat);
  EXPECT_FALSE(s.degenerate);
  EXPECT_NEAR(s.normal.norm(), 1.0, 1e-14);
  EXPECT_NEAR((s.point_b - s.point_a).norm(), s.distance, tol);
  EXPECT_LE((s.point_b - s.point_a - s.distance * s.normal).norm(), tol);
  // The plane through the closest points with the returned normal separates every corner, and the
  // supports' gap along it (a lower bound of the distance) is the distance.
  for (const Vec3& c : world_corners(a)) EXPECT_LE(s.normal.dot(c - s.point_a), tol);
  for (const Vec3& c : world_corners(b)) EXPECT_GE(s.normal.dot(c - s.point_b), -tol);
  EXPECT_NEAR(support_gap(a, b, s.normal), s.distance, std::min(tol, 1e-9));
  // The points belong to their hulls (so the distance is also an upper bound), and the exact
  // feature-pair distance agrees.
  EXPECT_LE(beyond_faces(ha, a, s.point_a), tol);
  EXPECT_LE(beyond_faces(hb, b, s.point_b), tol);
  EXPECT_NEAR(s.distance, reference_distance(ha, a, hb, b), tol);
}

// Everything an overlap answer promises: the witness points are the supports along the normal, no
// sampled direction (nor any face normal) has a smaller overlap, and moving B along the normal by
// the depth plus or minus delta leaves a gap, or an overlap, of exactly delta.
void expect_overlap(const Hull& ha, const PlacedHull& a, const Hull& hb, const PlacedHull& b, const Separation& s,
                    double tol, std::mt19937_64& rng) {
  EXPECT_TRUE(s.sat);
  EXPECT_FALSE(s.degenerate);
  EXPECT_NEAR(s.normal.norm(), 1.0, 1e-14);
  EXPECT_NEAR(s.normal.dot(s.point_b - s.point_a), s.distance, tol);
  EXPECT_NEAR(support_gap(a, b, s.normal), s.distance, tol);
  std::vector<Vec3> dirs;
  for (int i = 0; i < 300; ++i) dirs.push_back(random_unit(rng));
  for (const Vec3& n : ha.normals) dirs.push_back(a.R * n);
  for (const Vec3& n : hb.normals) dirs.push_back(b.R * n);
  double worst = -std::numeric_limits<double>::infinity();
  for (const Vec3& u : dirs) worst = std::max(worst, support_gap(a, b, u));
  EXPECT_LE(worst, s.distance + tol);
  const double delta = 1e-3;
  for (const double sign : {1.0, -1.0}) {
    PlacedHull moved = b;
    moved.x = b.x + (-s.distance + sign * delta) * s.normal;
    const Separation m = separation(a, moved);
    EXPECT_NEAR(m.distance, sign * delta, 1e-9) << "sign " << sign;
    if (sign > 0) {
      EXPECT_FALSE(m.sat);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Known cases

TEST(ConvexDistance, CubesFaceFace) {
  const Hull c = cube();
  for (const double gap : {1e-9, 1e-3, 0.25, 2.0}) {
    const PlacedHull a = c.placed(Mat3::Identity(), Vec3::Zero());
    const PlacedHull b = c.placed(Mat3::Identity(), Vec3(1.0 + gap, 0.3, -0.2));
    const Separation s = separation(a, b);
    EXPECT_NEAR(s.distance, gap, 1e-15 * (1.0 + gap)) << gap;
    EXPECT_LE((s.normal - Vec3::UnitX()).norm(), 1e-15) << gap;
    EXPECT_NEAR(s.point_a.x(), 0.5, 1e-15);
    EXPECT_NEAR(s.point_b.x(), 0.5 + gap, 1e-15);
    // On the faces' common patch, y in [-0.2, 0.5], z in [-0.5, 0.3].
    EXPECT_GE(s.point_a.y(), -0.2 - 1e-15);
    EXPECT_LE(s.point_a.z(), 0.3 + 1e-15);
    EXPECT_LE(s.iterations, 8);
    expect_separated(c, a, c, b, s, 1e-14);
  }
}

TEST(ConvexDistance, CubesEdgeEdgeCrossed) {
  // A turned 45 deg about y: its top is the edge along y at z = sqrt(1/2). B turned 45 deg about
  // x: its bottom is the edge along x, sqrt(1/2) below its centre.
  const Hull c = cube();
  const double h = std::sqrt(0.5);
  for (const double gap : {1e-6, 0.01, 0.7}) {
    const PlacedHull a = c.placed(rot_y(kPi / 4), Vec3::Zero());
    const PlacedHull b = c.placed(rot_x(kPi / 4), Vec3(0.2, -0.1, 2 * h + gap));
    const Separation s = separation(a, b);
    EXPECT_NEAR(s.distance, gap, 1e-15) << gap;
    EXPECT_LE((s.normal - Vec3::UnitZ()).norm(), 1e-12) << gap;
    EXPECT_LE((s.point_a - Vec3(0, -0.1, h)).norm(), 1e-15) << gap;
    EXPECT_LE((s.point_b - Vec3(0, -0.1, h + gap)).norm(), 1e-15) << gap;
    expect_separated(c, a, c, b, s, 1e-14);
  }
}

TEST(ConvexDistance, CubesCornerFace) {
  // A's corner (1,1,1)/2 turned to point up: at z = sqrt(3)/2, below B's bottom face.
  const Hull c = cube();
  const double h = std::sqrt(3.0) / 2;
  for (const double gap : {1e-7, 0.02, 1.5}) {
    const PlacedHull a = c.placed(turn(Vec3(1, 1, 1), Vec3::UnitZ()), Vec3::Zero());
    const PlacedHull b = c.placed(Mat3::Identity(), Vec3(0.1, 0.2, h + gap + 0.5));
    const Separation s = separation(a, b);
    EXPECT_NEAR(s.distance, gap, 1e-15) << gap;
    EXPECT_LE((s.normal - Vec3::UnitZ()).norm(), 1e-12) << gap;
    EXPECT_LE((s.point_a - Vec3(0, 0, h)).norm(), 1e-15) << gap;
    EXPECT_LE((s.point_b - Vec3(0, 0, h + gap)).norm(), 1e-15) << gap;
    expect_separated(c, a, c, b, s, 1e-14);
    // The same pair the other way round: the corner is B's, the normal flips.
    const Separation r = separation(b, a);
    EXPECT_NEAR(r.distance, gap, 1e-15);
    EXPECT_LE((r.normal + Vec3::UnitZ()).norm(), 1e-12);
    EXPECT_LE((r.point_b - Vec3(0, 0, h)).norm(), 1e-15);
  }
}

TEST(ConvexDistance, FarFromTheOrigin) {
  // The pair is solved in A's frame: a world position of 1000 sizes costs only its own rounding.
  const Hull c = cube();
  const Vec3 x(1000.0, -2000.0, 500.0);
  const PlacedHull a = c.placed(rot_x(0.3), x);
  const PlacedHull b = c.placed(rot_x(0.3), x + rot_x(0.3) * Vec3(0.2, 1.001, 0.1));
  const Separation s = separation(a, b);
  EXPECT_NEAR(s.distance, 1e-3, 1e-12);
  EXPECT_LE((s.normal - rot_x(0.3) * Vec3::UnitY()).norm(), 1e-9);
}

TEST(ConvexDistance, RotatedCubesAgainstReference) {
  std::mt19937_64 rng(20240601);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Hull small = cube(0.016), large = cube(0.03);
  for (int i = 0; i < 300; ++i) {
    const Hull& hb = i % 2 ? small : large;
    const PlacedHull a = small.placed(random_rotation(rng), Vec3(u01(rng), u01(rng), u01(rng)));
    PlacedHull b = hb.placed(random_rotation(rng), a.x);
    const Vec3 u = random_unit(rng);
    const double gap = 0.016 * std::pow(10.0, -6.0 * u01(rng));  // 1e-8 m .. 16 mm along u
    b.x += u * (gap - support_gap(a, b, u));                      // B's gap along u: exactly `gap`
    const Separation s = separation(a, b);
    expect_separated(small, a, hb, b, s, 1e-15);
    EXPECT_GE(s.distance, gap * (1 - 1e-12));  // a gap along one axis is a lower bound
    EXPECT_LE(s.iterations, 12);
  }
}

TEST(ConvexDistance, OverlappingCubesKnownDepth) {
  const Hull c = cube();
  std::mt19937_64 rng(7);
  struct Case {
    Mat3 Rb;
    Vec3 xb;
    double depth;
    Vec3 normal;
  };
  const double h = std::sqrt(0.5);
  const Case cases[] = {
      {Mat3::Identity(), Vec3(0.9, 0.3, 0.2), 0.1, Vec3::UnitX()},
      {Mat3::Identity(), Vec3(-0.95, 0.1, 0.1), 0.05, -Vec3::UnitX()},
      {rot_z(kPi / 4), Vec3(0.1, 0.05, 0.97), 0.03, Vec3::UnitZ()},
      {Mat3::Identity(), Vec3(0.01, -0.02, -0.6), 0.4, -Vec3::UnitZ()},
  };
  for (const Case& k : cases) {
    const PlacedHull a = c.placed(Mat3::Identity(), Vec3::Zero());
    const PlacedHull b = c.placed(k.Rb, k.xb);
    const Separation s = separation(a, b);
    EXPECT_NEAR(s.distance, -k.depth, 1e-14);
    EXPECT_LE((s.normal - k.normal).norm(), 1e-14);
    expect_overlap(c, a, c, b, s, 1e-14, rng);
  }
  // The crossed edges pushed 0.01 into each other: the edges' cross product is the axis.
  const PlacedHull a = c.placed(rot_y(kPi / 4), Vec3::Zero());
  const PlacedHull b = c.placed(rot_x(kPi / 4), Vec3(0.2, -0.1, 2 * h - 0.01));
  const Separation s = separation(a, b);
  EXPECT_NEAR(s.distance, -0.01, 1e-14);
  EXPECT_LE((s.normal - Vec3::UnitZ()).norm(), 1e-14);
  expect_overlap(c, a, c, b, s, 1e-14, rng);
}

TEST(ConvexDistance, TetrahedronVsCube) {
  const Hull c = cube();
  const double t = 0.3;
  const Hull tet = tetrahedron(t);
  std::mt19937_64 rng(11);
  // Which feature faces the cube's top, and how far it lies below the tetrahedron's centre.
  struct Down {
    Vec3 dir;
    double reach;
  };
  const Down downs[] = {{Vec3(1, 1, 1), t * std::sqrt(3.0)}, {Vec3(1, 0, 0), t}, {Vec3(-1, -1, -1), t / std::sqrt(3.0)}};
  for (const Down& d : downs) {
    const Mat3 R = turn(d.dir, -Vec3::UnitZ());
    for (const double gap : {1e-8, 0.05}) {
      const PlacedHull a = c.placed(Mat3::Identity(), Vec3::Zero());
      const PlacedHull b = tet.placed(R, Vec3(0.1, -0.05, 0.5 + d.reach + gap));
      const Separation s = separation(a, b);
      EXPECT_NEAR(s.distance, gap, 1e-15);
      EXPECT_LE((s.normal - Vec3::UnitZ()).norm(), 1e-12);
      expect_separated(c, a, tet, b, s, 1e-14);
    }
    // Pushed 0.02 into the top face: the face's normal is the least overlap.
    const PlacedHull a = c.placed(Mat3::Identity(), Vec3::Zero());
    const PlacedHull b = tet.placed(R, Vec3(0.1, -0.05, 0.5 + d.reach - 0.02));
    const Separation s = separation(a, b);
    EXPECT_NEAR(s.distance, -0.02, 1e-14);
    EXPECT_LE((s.normal - Vec3::UnitZ()).norm(), 1e-14);
    expect_overlap(c, a, tet, b, s, 1e-14, rng);
    // The tetrahedron as A: the same overlap seen from the other side.
    const Separation r = separation(b, a);
    EXPECT_NEAR(r.distance, -0.02, 1e-14);
    EXPECT_LE((r.normal + Vec3::UnitZ()).norm(), 1e-14);
  }
}

TEST(ConvexDistance, PointDistance) {
  const Hull c = cube();
  const Mat3 R = turn(Vec3(1, 2, 3), Vec3(-1, 0.5, 0.2));
  const Vec3 x(0.3, -1.2, 2.0);
  const PlacedHull h = c.placed(R, x);
  struct Case {
    Vec3 p, closest;  // the hull's own frame
    double distance;
  };
  const Case cases[] = {
      {{2, 0, 0}, {0.5, 0, 0}, 1.5},
      {{1, 1, 1}, {0.5, 0.5, 0.5}, std::sqrt(0.75)},
      {{1, 0.2, 0.7}, {0.5, 0.2, 0.5}, std::sqrt(0.29)},
      {{0.3, 0, 0}, {0.5, 0, 0}, -0.2},
      {{0.1, -0.4, 0.05}, {0.1, -0.5, 0.05}, -0.1},
      {{0.5, 0.1, 0.1}, {0.5, 0.1, 0.1}, 0.0},
  };
  for (const Case& k : cases) {
    Vec3 closest;
    const double d = point_distance(h, R * k.p + x, &closest);
    EXPECT_NEAR(d, k.distance, 1e-14) << k.p.transpose();
    EXPECT_LE((closest - (R * k.closest + x)).norm(), 1e-14) << k.p.transpose();
  }
  // The centre: half a side deep, closest on some face's centre.
  Vec3 closest;
  EXPECT_NEAR(point_distance(h, x, &closest), -0.5, 1e-14);
  EXPECT_NEAR((R.transpose() * (closest - x)).cwiseAbs().maxCoeff(), 0.5, 1e-14);
  EXPECT_NEAR((closest - x).norm(), 0.5, 1e-14);
}

TEST(ConvexDistance, PointsAndSegments) {
  // Degenerate hulls: the Minkowski difference of two segments is a flat parallelogram, of a point
  // and a segment a segment.
  const std::vector<Vec3> point{Vec3::Zero()};
  const std::vector<Vec3> rod{Vec3(-1, 0, 0), Vec3(1, 0, 0)};
  PlacedHull a, b;
  a.corners = point;
  b.corners = point;
  b.x = Vec3(0.3, -0.4, 1.2);
  Separation s = separation(a, b);
  EXPECT_NEAR(s.distance, 1.3, 1e-15);
  EXPECT_LE((s.normal - b.x / 1.3).norm(), 1e-15);
  a.corners = rod;
  b.corners = rod;
  b.R = rot_z(kPi / 2);  // crossed at 90 deg, 0.3 apart
  b.x = Vec3(0.2, 0.1, 0.3);
  s = separation(a, b);
  EXPECT_NEAR(s.distance, 0.3, 1e-15);
  EXPECT_LE((s.normal - Vec3::UnitZ()).norm(), 1e-15);
  EXPECT_LE((s.point_a - Vec3(0.2, 0, 0)).norm(), 1e-15);
  EXPECT_LE((s.point_b - Vec3(0.2, 0, 0.3)).norm(), 1e-15);
  EXPECT_FALSE(s.degenerate);
  b.corners = point;  // the point beyond the rod's end
  b.x = Vec3(1.5, 0.0, 1.2);
  s = separation(a, b);
  EXPECT_NEAR(s.distance, 1.3, 1e-15);
  EXPECT_LE((s.point_a - Vec3(1, 0, 0)).norm(), 1e-15);
  // Crossing rods overlap, and with no faces or edges given the SAT has no axis: reported.
  b.corners = rod;
  b.x = Vec3(0.2, 0.1, 0.0);
  s = separation(a, b);
  EXPECT_TRUE(s.sat);
  EXPECT_TRUE(s.degenerate);
  EXPECT_EQ(s.distance, 0.0);
}

TEST(ConvexDistance, SwappedOrderAgrees) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Hull c = cube(), tet = tetrahedron(0.4);
  for (int i = 0; i < 200; ++i) {
    const PlacedHull a = c.placed(random_rotation(rng), Vec3::Zero());
    const PlacedHull b = tet.placed(random_rotation(rng), random_unit(rng) * (0.3 + 1.5 * u01(rng)));
    const Separation s = separation(a, b), r = separation(b, a);
    EXPECT_NEAR(s.distance, r.distance, 1e-14);
    EXPECT_LE((s.normal + r.normal).norm(), s.distance > 0 ? 1e-12 : 1e-14);
    if (s.distance > 0) {
      EXPECT_LE((s.point_a - r.point_b).norm(), 1e-12);
      EXPECT_LE((s.point_b - r.point_a).norm(), 1e-12);
    }
  }
}

// 2000 random pairs of random point clouds (interior points included as corners), random sizes,
// aspect ratios, orientations and placements: separated by 1e-9 to 1 along a random axis, at
// random offsets (either), overlapping by up to 0.5 along a random axis (mostly overlapping), and
// with their origins within 0.3 (overlapping).
TEST(ConvexDistance, RandomPairs) {
  std::mt19937_64 rng(0x5eed'd1ce);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto cloud = [&] {
    const int n = 4 + static_cast<int>(rng() % 13);
    const Vec3 size(0.2 + 1.8 * u01(rng), 0.2 + 1.8 * u01(rng), 0.2 + 1.8 * u01(rng));
    std::vector<Vec3> pts;
    for (int i = 0; i < n; ++i) pts.push_back(size.cwiseProduct(Vec3(2 * u01(rng) - 1, 2 * u01(rng) - 1, 2 * u01(rng) - 1)));
    return hull_of(pts);
  };
  int separated = 0, overlapping = 0, max_iterations = 0;
  for (int i = 0; i < 2000; ++i) {
    const Hull ha = cloud(), hb = cloud();
    const PlacedHull a = ha.placed(random_rotation(rng), 10.0 * Vec3(u01(rng) - 0.5, u01(rng) - 0.5, u01(rng) - 0.5));
    PlacedHull b = hb.placed(random_rotation(rng), a.x);
    const Vec3 u = random_unit(rng);
    switch (i % 4) {
      case 0: b.x += u * (std::pow(10.0, -9.0 * u01(rng)) - support_gap(a, b, u)); break;
      case 1: b.x += u * (4.0 * u01(rng)); break;
      case 2: b.x += u * (-0.5 * u01(rng) - support_gap(a, b, u)); break;
      default: b.x += u * (0.3 * u01(rng)); break;
    }
    const Separation s = separation(a, b);
    max_iterations = std::max(max_iterations, s.iterations);
    SCOPED_TRACE(i);
    if (!s.sat) {
      ++separated;
      expect_separated(ha, a, hb, b, s, 1e-13);
    } else {
      ++overlapping;
      expect_overlap(ha, a, hb, b, s, 1e-13, rng);
    }
    if (::testing::Test::HasFailure()) break;  // one case's report, not two thousand
  }
  EXPECT_GT(separated, 700);
  EXPECT_GT(overlapping, 700);
  EXPECT_LE(max_iterations, 20);
  std::printf("random pairs: %d separated, %d overlapping, at most %d GJK iterations\n", separated, overlapping,
              max_iterations);
}

}  // namespace
}  // namespace dicesim

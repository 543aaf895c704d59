// The narrow phase between two convex polytopes: their separation distance and closest points by
// GJK (the signed-volumes sub-algorithm of Montanari, Petrinic and Barbieri 2017), and once they
// overlap, the penetration depth and its axis by the separating-axis test. Conservative advancement
// needs the distance, which libccd does not give.
#pragma once

#include <array>
#include <span>

#include "sim/math.hpp"

namespace dicesim {

// A convex polytope placed in the world: its corners in its own frame, rotation R (own -> world)
// and the position x of its frame's origin. For the SAT overlap case, its outward face normals and
// its edge directions in its own frame (unit; edges: one per parallel class is enough; extra
// directions, both signs of a normal, or face diagonals only cost time). At least one corner.
// Corners may include points inside the hull (they never win a support search).
struct PlacedHull {
  std::span<const Vec3> corners;
  std::span<const Vec3> face_normals;
  std::span<const Vec3> edge_dirs;
  Mat3 R = Mat3::Identity();
  Vec3 x = Vec3::Zero();
};

struct Separation {
  // > 0: Euclidean distance between the two hulls; <= 0: they overlap, minus the penetration
  // depth along `normal` (SAT). A SAT answer (`sat`) may be positive by ~1e-12 of the sizes: hulls
  // that touch to GJK's tolerance are handed to the SAT, which then reports their gap along its axis.
  double distance = 0.0;
  // Unit, pointing from A toward B (moving B along +normal by -distance separates them when
  // overlapping).
  Vec3 normal = Vec3::UnitZ();
  // World: the closest points (separated); overlapping: A's deepest corner along +normal and B's
  // deepest corner along -normal, i.e. the witness points of the SAT axis (normal . (point_b -
  // point_a) == distance either way).
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();
  int iterations = 0;       // GJK iterations
  bool degenerate = false;  // GJK hit its iteration cap or a numerical stall and returned its best
                            // estimate, or an overlap had no SAT axes to test (the caller counts this)
  bool sat = false;         // the answer is the SAT's (overlap, or touching within GJK's tolerance)
};

// The corners of the simplex a separated pair ended with, to start the same pair's next call from
// (a warm start: a pair that moved a little since converges in an iteration or two instead of
// five or six). n = 0: none (a cold start from the support toward B).
struct SeparationCache {
  std::array<int, 4> ia{}, ib{};
  int n = 0;
};

// `cache` (optional) is read to start from and written with the final simplex: up to 3 corners if
// separated; if overlapping, the simplex that held the origin (4 corners, or fewer if it touched),
// from which a pair still overlapping, as a touching pair measured again mostly is, is known to at
// once.
Separation separation(const PlacedHull& a, const PlacedHull& b, SeparationCache* cache = nullptr);

// Distance from a world point to a placed hull (>0 outside, <=0 inside: minus the depth to the
// nearest face) and the closest point (inside: the point's projection onto that face's plane).
double point_distance(const PlacedHull& h, const Vec3& p, Vec3* closest = nullptr);

}  // namespace dicesim

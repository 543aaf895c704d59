// Where two convex polytopes touch, as up to four points: the contact patch of a touch whose
// normal the narrow phase found. Each body's feature at the touch is its corners within a slab of
// its surface's plane there (a corner, an edge, or a face); seen along the normal, the patch is
// the overlap of the two features: each one's corners inside the other, and the crossings of
// their edges; of more than four, the four that span them (the two farthest apart, then the
// farthest from their line on either side). A die's edge lying across another's face touches at
// the two points where it leaves the face, which are corners of neither body; a face on a face at
// the corners of their overlap.
// (A witness point alone may be any point of such a patch; the bodies' spin moves the patch's ends
// differently, and striking one point leaves the others approaching.)
#pragma once

#include <array>
#include <span>

#include "sim/math.hpp"

namespace dicesim {

inline constexpr int kMaxPatchPoints = 4;

struct ContactPatch {
  std::array<Vec3, kMaxPatchPoints> points;  // world, on the plane midway between the two surfaces
  int n = 0;
};

// A side of the touch: its corners (world; the centres of its rounded corners) and rounding. An
// empty `corners` is a half-space (a plane obstacle): every point of the other's feature is over it.
struct PatchSide {
  std::span<const Vec3> corners;
  double rounding = 0.0;
};

// Body a lies at n . x >= level_a (its surface's plane at the touch), body b at n . x <= level_b
// (n unit, from b into a). A corner belongs to its body's feature within `slab` of its plane; two
// points closer than `slab` (across the normal) are one.
ContactPatch contact_patch(const PatchSide& a, const PatchSide& b, const Vec3& n, double level_a, double level_b,
                           double slab);

}  // namespace dicesim

// Exact mass, centre of mass and inertia tensor of a box cut by planes into regions of
// constant density. Exact: each region is a convex polyhedron (the box clipped by half-spaces)
// and its volume integrals are evaluated in closed form, not sampled.
#pragma once

#include <array>
#include <vector>

#include "sim/body/shape.hpp"
#include "sim/math.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// Volume integrals of a convex polyhedron with unit density, about the frame's origin.
struct VolumeMoments {
  double volume = 0.0;
  Vec3 first = Vec3::Zero();   // integral of x dV
  Mat3 second = Mat3::Zero();  // integral of x x^T dV
};

// The box [-size/2, size/2] intersected with all `cuts` (each n.x <= d). Empty -> all zeros.
VolumeMoments clipped_box_moments(const Vec3& size, const std::vector<HalfSpace>& cuts);

// The same for an arbitrary axis-aligned box [lo, hi] (used for a corner's small neighbourhood).
VolumeMoments clipped_aabb_moments(const Vec3& lo, const Vec3& hi, const std::vector<HalfSpace>& cuts);

// Volume moments of the solid a closed surface bounds, intersected with all `cuts`, exact (up to
// rounding): each cut clips the triangles and closes the cut with a cap fanned from one point of
// its outline, which is right for any closed surface, convex or not, and any number of cap loops.
VolumeMoments clipped_surface_moments(const Triangles& surface, const std::vector<HalfSpace>& cuts);

// The closed surface of that intersection (triangles; the caps fanned from one point each).
Triangles clipped_surface(const Triangles& surface, const std::vector<HalfSpace>& cuts);

// The same without cuts: the divergence theorem, tetrahedra from the vertex mean to each triangle.
VolumeMoments surface_moments(const Triangles& surface);

void accumulate(VolumeMoments& total, const VolumeMoments& part, double weight);

struct MassProperties {
  double mass = 0.0;           // kg
  Vec3 com = Vec3::Zero();     // in the geometric frame (m)
  Mat3 inertia = Mat3::Zero(); // about the COM, geometric axes (kg m^2), products of inertia included
  Vec3 principal_moments = Vec3::Zero();  // ascending
  Mat3 principal_axes = Mat3::Identity(); // columns: principal axes in the geometric frame, right-handed
};

// Density field: die.base_material everywhere, except inside each region (die.regions), where
// that region's material holds. Regions are assumed already validated as non-overlapping.
MassProperties compute_mass_properties(const DieDef& die, const std::map<std::string, MaterialDef>& materials);

// Mass properties from density-weighted volume moments (mass, int rho x dV, int rho x x^T dV):
// COM, inertia about it, principal frame (deterministic, see mass_properties.cpp). No mass: only
// `mass` is set.
MassProperties mass_properties_from_moments(const VolumeMoments& weighted);

// Inertia tensor about the origin from volume moments and density: rho * (tr(S) I - S).
Mat3 inertia_from_second_moment(const Mat3& second, double density);

}  // namespace dicesim

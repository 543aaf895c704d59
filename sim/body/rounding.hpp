// Rounded edges and corners: the die is its core (every face plane moved in by r) swept by a ball
// of radius r, so that its flat faces stay where the scene puts them. Mass properties exactly:
// core + one slab per face + one cylinder wedge per edge + one ball sector per corner, each in
// closed form (derivation in rounding.cpp).
#pragma once

#include <vector>

#include "sim/body/mass_properties.hpp"
#include "sim/body/shape.hpp"

namespace dicesim {

// The core of `outer` rounded with radius r > 0: the intersection of the half-spaces
// n.x <= d - r over outer's faces. Throws HullError when nothing solid is left (r not below the
// inradius). A face narrower than 2 r disappears from the core (its label with it).
ConvexShape shrink_shape(const ConvexShape& outer, double r);

// The radius of the largest ball inside `outer` (bisection on shrink_shape to 1e-9 relative; for
// messages only).
double inradius(const ConvexShape& outer);

// The solid core (+) ball(r), cut into the closed-form pieces above.
class RoundedSolid {
 public:
  RoundedSolid(const ConvexShape& core, double r);

  // Volume moments of the rounded solid intersected with `cuts`. Exact for the core and the face
  // slabs (polytopes, clipped). An edge wedge is first cut exactly along its length by the cuts
  // whose plane is perpendicular to the edge (a slab parallel to a box's face); what is left of it,
  // and each corner sector, is counted whole when its centroid satisfies every other cut and left
  // out otherwise. So the result is exact unless a cut crosses a rounded edge obliquely or a
  // rounded corner, and then off by at most the volume of the curved pieces it crosses. Without
  // cuts it is exact.
  VolumeMoments moments(const std::vector<HalfSpace>& cuts) const;

  // Steiner's formula: V + S r + (sum over edges of L theta / 2) r^2 + 4/3 pi r^3 (theta: the
  // angle between the edge's face normals). For tests: computed apart from the pieces' moments.
  double steiner_volume() const { return steiner_volume_; }

 private:
  struct Wedge {
    Vec3 a, b, n1, n2;
  };
  double r_ = 0.0;
  Triangles core_;
  std::vector<Triangles> slabs_;
  std::vector<Wedge> wedges_;
  std::vector<VolumeMoments> corners_;
  double steiner_volume_ = 0.0;
};

// Moments of pieces, exposed for tests against quadrature.
// Edge wedge: { a + s e + rho (cos(phi) u + sin(phi) w) : s in [0, L], rho in [0, r], phi in [0, theta] }
// with e = (b - a)/L, u the first face's normal, w the unit vector perpendicular to e and u that
// turns u towards the second face's normal v by theta.
VolumeMoments edge_wedge_moments(const Vec3& a, const Vec3& b, const Vec3& u, const Vec3& v, double r);
// Corner sector: { p + rho n : rho in [0, r], n in the spherical polygon of the face normals
// around corner p }. `face_angles`: the corner's angle on each face around it; `edges`: each edge
// at p as (unit direction away from p, normal of one face, normal of the other).
struct CornerEdge {
  Vec3 direction, n1, n2;
};
VolumeMoments corner_sector_moments(const Vec3& p, double sum_face_angles, const std::vector<CornerEdge>& edges,
                                    double r);

}  // namespace dicesim

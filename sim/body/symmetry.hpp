// Outcomes alike by design: the die's symmetries (proper rotations about its centre of mass that
// carry its shape and its material layout onto themselves) and the classes of outcomes they
// exchange. Only such outcomes have equal probabilities by design; a chi-square "against fair" is
// meaningful within a class and nowhere else (apps/report.cpp).
//
// Why rotations suffice, and why the throw matters: if a rotation S carries the die onto itself,
// orientations R and R S put the very same body in the same place, so every toss from R S is a
// toss from R with the faces renamed by S. With a uniform (Haar) orientation R S is as likely as
// R, so outcomes exchanged by S are equally likely, whatever the physics. A throw drawn any other
// way (fixed or Euler-uniform orientation) gives no such guarantee, and a spin about a body axis
// keeps only the rotations that fix that axis. Reflections are not used: a mirror image is a
// different toss unless the throw is mirror-symmetric too.
#pragma once

#include <string>
#include <vector>

#include "sim/body/body.hpp"
#include "sim/math.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

struct DieSymmetry {
  std::vector<Mat3> rotations;  // geometric frame, about the COM; the identity first
  std::string note;             // how they were found, or why none beyond the identity was looked for
};

// The proper rotations that map the die onto itself: its corners (a cylinder: its rims) and, at
// 4096 quasi-random points inside it, its material (density, restitution, friction, rolling and
// pivoting resistance; a mesh that is not convex: inside or outside the solid), its inertia tensor
// and its corners' contact materials, all to 1e-7 of its size (relative). Then those the throw
// keeps (see above). More than 400 corners: not looked for (note says so).
DieSymmetry die_symmetry(const Body& body, const SceneDef& scene);

// Per outcome (the distinct face labels ascending), the index of its class of alike outcomes:
// outcomes A and B are alike when a rotation carries the faces labelled A onto those labelled B.
// A class is numbered by its first outcome's index.
std::vector<int> alike_outcome_classes(const Body& body, const std::vector<Mat3>& rotations);

}  // namespace dicesim

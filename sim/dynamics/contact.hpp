// Impacts with the floor.
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/dynamics/flight.hpp"

namespace dicesim {

struct Impact {
  double impulse = 0.0;  // normal impulse (N s), >= 0
  Vec3 contact_point = Vec3::Zero();  // world, relative to the COM
};

// Frictionless single-vertex impact (the `paper` model, corrected): the impulse acts on the
// contact point's velocity v + omega x r with the world inertia tensor, and restitution e of
// that vertex:  j = -(1 + e) v_c.n / (1/m + n.[(I_w^-1 (r x n)) x r]),  n = +z.
// Updates s.velocity and s.omega in place. A vertex that is not approaching gets no impulse.
Impact apply_vertex_impact(const DieModel& m, RigidState& s, int vertex);

// Kinetic energy of a state (translation + rotation).
double kinetic_energy(const DieModel& m, const RigidState& s);

}  // namespace dicesim

// Impacts and sustained contacts with Coulomb friction against the floor (z = 0, normal +z):
// the impact law shared by the `impulse` and `stepped` fidelities.
//
//  - One contact point: the perfectly plastic frictional impulse first (exact: the sticking impulse
//    P_I = -W^-1 u if |P_I,t| <= mu P_I,n, W the contact compliance and u the contact-point velocity
//    v + w x r; else sliding with maximal dissipation, zero final normal velocity, the slip
//    direction found as a bracketed root in its angle; only a jam falls back to PGS). Then
//    restitution e of that corner: sticking -> Chatterjee & Ruina (1998) with tangential
//    restitution 0, P = P_I + e (P_I.n) n; sliding -> Poisson, P = (1 + e) P_slide. (CR's own
//    projection of (1+e) P_I,n n + P_I,t onto the cone keeps the sticking normal impulse and makes
//    plastic sliding impacts rebound fast; the sliding branch avoids that.) mu = 0: the
//    frictionless Newton impulse of `paper`.
//  - Several simultaneous contacts (an edge: 2, a face: 4) are solved together: the plastic
//    frictional impact (Coulomb cone at every point, non-negative separation, complementarity)
//    by projected Gauss-Seidel over the points, then Poisson restitution: normal impulses e_i P_n,i.
//  - Every impact is checked against the kinetic energy before it: should the result gain energy
//    (which a frictional multi-contact Poisson law can do in rare configurations), the impulse is
//    scaled back to the largest fraction that does not. So no impact ever creates energy.
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/dynamics/flight.hpp"

namespace dicesim {

// A face of more corners touches at the kMaxContacts lowest (enough to carry any load on a
// flat floor; a many-sided face is rare: a prism's end, a hull's big face).
inline constexpr int kMaxContacts = 16;

// The corners of the die that touch the floor at one instant.
struct ContactSet {
  int n = 0;
  int vertex[kMaxContacts] = {};
};

struct ImpactResult {
  double normal_impulse = 0.0;  // sum over the points (N s)
  double energy_before = 0.0;   // kinetic energy (J)
  double energy_after = 0.0;
  bool energy_clamped = false;  // the energy guard scaled the impulse back
};

// Corners of `s` whose contact point (the lowest point of the corner's ball) is at most `tol` (m)
// above the floor; of more than kMaxContacts, the lowest.
ContactSet touching_corners(const DieModel& m, const RigidState& s, double tol);

// Impact with restitution (true) or perfectly plastic (false, used for sustained contact), with
// Coulomb friction. Updates s.velocity and s.omega; positions are untouched.
ImpactResult apply_friction_impact(const DieModel& m, RigidState& s, const ContactSet& c, bool restitution);

// Velocity of corner `vertex`'s contact point (world).
inline Vec3 corner_velocity(const DieModel& m, const RigidState& s, int vertex) {
  return s.velocity + s.omega.cross(contact_point(m, s.R, vertex));
}

}  // namespace dicesim

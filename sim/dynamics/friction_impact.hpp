// Impacts and sustained contacts with Coulomb friction against the floor (z = 0, normal +z):
// the impact law shared by the `impulse` and `stepped` fidelities, for any number of touching
// corners (one corner, an edge, a face of any polygon), in two phases with friction in both:
//
//  1. Compression: the perfectly plastic frictional impact. At every point P_n >= 0, u_n >= 0,
//     P_n u_n = 0, |P_t| <= mu P_n, sticking if the impulse fits the cone, else sliding with the
//     friction opposite the final slip (maximal dissipation). One point: exact (sticking
//     P = -W^-1 u, else a bracketed root in the slip direction; W the contact compliance
//     (1/m) 1 - [r]x I_w^-1 [r]x, u the point's velocity v + w x r). Several (a polyhedron's or a rim's):
//     first directly, if every point of an edge or a triangle slides (or lifts), or if every point
//     sticks (friction_exact_plastic.cpp: solve_sliding, solve_sticking; accepted only where Coulomb's
//     law verifies; a rim's only when every point slips past mu times its approach); else projected
//     Gauss-Seidel where every update is the exact minimiser of the kinetic energy over its own
//     block (normal: P_n >= 0; tangential: the disc |P_t| <= mu P_n, in the metric of W_tt), so
//     every sweep lowers the energy; warm-started, symmetric sweeps, converged to 1e-11 of the
//     speeds; a solve still unconverged at the sweep cap (an edge near the stick-slip boundary:
//     two corners' compliance has rank 5) is finished by semismooth Newton on the Alart-Curnier
//     equations; two points it leaves unconverged (a coin on its side, its two rims' lowest points
//     touching close together: friction_exact_plastic.cpp, solve_plastic_pair) are solved exactly by
//     their active sets (both stick, one sticks and one slides, both slide), and a solve is
//     counted (pgs_unconverged) only if that fails too. The lever arms of a
//     multi-point solve lie in one contact plane (the lowest point's height) when its points are
//     within 1e-6 r of it: corners touching within the tolerance but out of level by ~1e-9 m
//     made a face's problem inconsistent.
//  2. Restitution, energetic (Stronge): the normal impulses of compression, scaled by one k,
//     release e^2 times the energy compression stored in the normal direction, where that is
//     E_c = min(-W_n, -dE_c): W_n the work of the normal impulses along the compression (straight
//     impulse path, so exact), dE_c the kinetic energy change of compression (W_n alone can
//     exceed what compression removed when W couples normal and slip: returning e^2 W_n would
//     then gain energy, the flaw of Chatterjee-Ruina's P_I + e P_In n at high e). Then friction
//     again, in the discs |P_t| <= mu k P_n, minimising the kinetic energy (Coulomb with
//     maximal dissipation against the restitution's slip; on an edge, two points, solved exactly by
//     its active sets (both stick / one slides / both slide) and verified against the KKT
//     conditions, Gauss-Seidel and Newton only if no case verifies; the same exact solve when those
//     fail and only two points carry friction). Mixed materials: one e for the impact,
//     sum w_i e_i / sum w_i with w_i the approach speed of point i before the impact, a function of
//     the state alone (not of the Gauss-Seidel split of a face's load, which is not unique).
//  So dE = dE_c + e^2 E_c + (friction <= 0) <= (1 - e^2) dE_c <= 0 for any e in [0, 1], any number
//  of points, converged or not. mu = 0, one point: the Newton impulse of `paper` exactly.
//  Should the restitution leave a point approaching (a restitution impulse tipping a neighbour
//  into the floor), one more plastic pass stops it; if even that fails, a frictionless plastic
//  solve (always dissipative), counted as a fallback. The energy guard is kept as an assertion:
//  it scales an impulse back only if rounding broke the proof, and counts it (energy_clamps).
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/dynamics/corrections.hpp"
#include "sim/dynamics/flight.hpp"

namespace dicesim {

// Simultaneous contact points one solve handles: a face of more corners touches at the
// kMaxContacts lowest (enough to carry any load on a flat floor; no ready scene reaches it).
inline constexpr int kMaxContacts = 32;

// The corners of the die that touch the floor at one instant.
struct ContactSet {
  int n = 0;
  int vertex[kMaxContacts] = {};
  int dropped = 0;  // touching corners left out beyond kMaxContacts: the impact counts a fallback
};

// Impulses per point of one solve (world: x, y tangential, z normal), in the ContactSet's order.
struct ContactImpulses {
  int n = 0;
  int vertex[kMaxContacts] = {};
  Vec3 P[kMaxContacts];
};

// The contact points of one solve: lever arms, materials and the compliance blocks W (the
// velocity change of the points per unit impulse), all functions of the orientation alone.
struct ContactPoints {
  int n = 0;
  Vec3 r[kMaxContacts];
  double e[kMaxContacts], mu[kMaxContacts];
  double inv_wnn[kMaxContacts];              // 1 / W_nn
  Eigen::Matrix2d wtt[kMaxContacts];         // tangential 2x2 block of W
  Eigen::Matrix2d inv_wtt[kMaxContacts];     // its inverse
  Mat3 W0;                                   // full compliance of point 0 (single-contact law)
  Mat3 W0_inverse;                           // its inverse (set for one point only)
  // The body's response to a unit impulse at point i along x, y, z: angular velocity
  // I_w^-1 (r x e_k), and the point's own velocity change along z (W's third column). The
  // sweeps apply their impulses through these (no cross products or 3x3 products per update).
  Vec3 ax[kMaxContacts], ay[kMaxContacts], az[kMaxContacts], wz[kMaxContacts];
  // Whether inv_wtt, ax, ay, az and wz are set: one point's exact solve needs none of them, so
  // they are filled only when its solve falls back to the sweeps (set_up_geometry's caller).
  bool sweep_terms = false;
};

// A solve's set-up for one orientation and contact set: the world inertia, its inverse and the
// points. Filled by the first apply_friction_impact given it (valid); solves of the same set at
// the same orientation, at other velocities, reuse it (the stepper's trial steps). The caller
// clears `valid` whenever the orientation or the set changes.
struct ContactGeometry {
  bool valid = false;
  // Iw already holds world_inertia(m, R) (the caller computed it for the same R): the set-up
  // keeps it. A caller that sets it stores Iw anew with every orientation (FixedStepper::step).
  bool iw_given = false;
  Mat3 Iw = Mat3::Identity(), inv_inertia = Mat3::Identity();
  ContactPoints pts;
};

struct ImpactResult {
  double normal_impulse = 0.0;  // sum over the points (N s)
  double energy_before = 0.0;   // kinetic energy (J)
  double energy_after = 0.0;
  int iterations = 0;           // Gauss-Seidel sweeps (both phases; 0 for an exact one-point solve)
  int dual_solves = 0;          // restitution friction taken by the dual solve after Gauss-Seidel stalled (verified, exact)
  // Solves whose first method failed and a second one took (the same law: not a correction,
  // reported): a one-point slide's Newton failed and its reference solve
  // (one_corner_sliding_reference) took it; a one-point jam (no sliding direction) taken by the
  // sweeps, converged; the sweeps stalled and an edge's or a pair's exact solve took it (the
  // dual's are dual_solves).
  int exact_fallbacks = 0;
  Corrections corrections;      // energy clamp, unconverged solve, fallback of this impact
};

// Corners of `s` whose contact point (the lowest point of the corner's ball) is at most `tol` (m)
// above the floor; of more than kMaxContacts, the lowest.
ContactSet touching_corners(const DieModel& m, const RigidState& s, double tol);

// Impact with restitution (true) or perfectly plastic (false, used for sustained contact), with
// Coulomb friction. Updates s.velocity and s.omega; positions are untouched. `warm`: impulses of
// a previous solve (matched by vertex) to start the compression from; `out`: the impulse at every
// point (compression plus restitution); `geometry`: the set-up shared with other solves of c at
// s.R (see ContactGeometry). All optional. `direct`: a multi-point plastic solve first tries the
// direct solves (every point sliding or lifting, then every point sticking; friction_exact_plastic.cpp;
// a curved die's only when every point slips past mu times its approach); false: always the
// Gauss-Seidel sweeps (the tests compare the two).
ImpactResult apply_friction_impact(const DieModel& m, RigidState& s, const ContactSet& c, bool restitution,
                                   const ContactImpulses* warm = nullptr, ContactImpulses* out = nullptr,
                                   ContactGeometry* geometry = nullptr, bool direct = true);

// The same impact law at given contact points: r[i] the lever arm (world, from the COM) of point i,
// c.vertex[i] the feature whose materials it has (a cylinder's rim points between its features:
// FixedStepper's rim strike). `warm` and `out` as apply_friction_impact's (matched by c.vertex).
ImpactResult apply_friction_impact_at(const DieModel& m, RigidState& s, const ContactSet& c, const Vec3* r,
                                      bool restitution, const ContactImpulses* warm = nullptr,
                                      ContactImpulses* out = nullptr);

// The one-corner plastic sliding impulse P = lambda (mu d, 1) (d a unit friction direction):
// zero final normal velocity u + W P, final slip anti-parallel to d. W the point's compliance, u
// its velocity before (u_z < 0), d0 the starting direction (opposite the slip before). The
// impact law uses the Newton solve (Halley's third-order step near the root) and falls back to the reference (a fixed point on d, then a
// root search in its angle) where Newton's root does not verify; both exposed for the tests
// that compare them. False: no root (Newton: none verified; reference: a jam).
// (iterations: set to the number of residual evaluations before the verification.)
bool one_corner_sliding_newton(const Mat3& W, const Vec3& u, double mu, Eigen::Vector2d d0, Vec3& P,
                               int* iterations = nullptr);
// (by_angle: set when the reference needed its angle search.)
bool one_corner_sliding_reference(const Mat3& W, const Vec3& u, double mu, Eigen::Vector2d d0, Vec3& P,
                                  bool* by_angle = nullptr);

// Velocity of corner `vertex`'s contact point (world).
inline Vec3 corner_velocity(const DieModel& m, const RigidState& s, int vertex) {
  return s.velocity + s.omega.cross(contact_point(m, s.R, vertex));
}

}  // namespace dicesim

// One contact point between two rigid bodies (two dice, or a die and a fixed obstacle): the floor's
// one-point impact law (friction_impact.hpp: plastic frictional compression, energetic restitution
// with friction in the disc mu k P_n, the energy check) with the point's relative velocity and the
// two bodies' combined compliance in place of the die's. For one point the law depends on nothing
// else: W = (1/m_a + 1/m_b) 1 - [r_a]x Ia^-1 [r_a]x - [r_b]x Ib^-1 [r_b]x (world inverse inertias;
// a fixed body contributes nothing), u = (v_a + w_a x r_a) - (v_b + w_b x r_b), and an impulse P
// (+P on A, -P on B) changes the two bodies' kinetic energy by u.P + P.W.P / 2, as for one body.
#pragma once

#include "sim/dynamics/corrections.hpp"
#include "sim/math.hpp"

namespace dicesim {

// One body's side of a contact: its state (velocity and angular velocity are updated), inverse mass
// and world inverse inertia (both zero: an immovable body; its velocities, zero for a fixed obstacle,
// count in u and receive only zeros), and the contact point's lever arm from its COM (world).
struct PairSide {
  Vec3* velocity;
  Vec3* omega;
  double inv_mass;
  Mat3 inv_inertia;
  Vec3 r;
};

struct PairImpactResult {
  Vec3 P = Vec3::Zero();  // impulse on A (world; the contact frame's for point_impact); B received -P
  // The kinetic energy of the relative motion at the point, u.W^-1 u / 2 (what a sticking plastic
  // impulse would remove), before and after: their difference is exactly (up to rounding) the
  // change of the two bodies' total kinetic energy, which needs no masses or inertias to state.
  double energy_before = 0.0, energy_after = 0.0;
  bool sliding = false;     // compression ended sliding (the sticking impulse left the cone)
  // Solves whose first method failed and a second took (the same law, as ImpactResult's): the Newton
  // slide's root did not verify and the reference took it, or a jam (neither found a sliding
  // direction) was solved as a root in the normal impulse (pair_impact.cpp).
  int exact_fallbacks = 0;
  // energy_clamps: the final energy check had to scale back; fallbacks: a frictionless impulse had to
  // stop the point (a jam with no root, or the point still approaching after a second plastic pass).
  Corrections corrections;
};

// n: unit contact normal pointing from B into A (A's side). Does nothing (P = 0) if the point is not
// approaching (u.n >= 0). e in [0, 1], mu >= 0.
PairImpactResult apply_pair_impact(PairSide a, PairSide b, const Vec3& n, double e, double mu);

// The law itself, in the contact frame (x, y tangential, z the normal from B into A): the impulse
// for compliance W (symmetric positive definite) and relative velocity u before. Returns P in that
// frame; nothing if u.z >= 0. apply_pair_impact is this in the frame built from n.
PairImpactResult point_impact(const Mat3& W, const Vec3& u, double e, double mu);

}  // namespace dicesim

// Coming to rest on a curved die (a cylinder): its resting geometry, the quasi-static roll, the
// "outcome settled" rule, and rolling resistance. Faces of a cylinder model: 0 = the heads face
// (normal +axis), 1 = the tails face, 2 = the curved side; "face f down" = lying on it.
//
// The COM height of the cylinder standing on the floor with body-frame down direction d is its
// support function  sigma(d) = o.d + b |d.k| + a |d - (d.k) k| + r  (o: geometric centre from the
// COM, k: axis, a, b: core rim radius and half-height, r: rounding). Faces are its minima at
// d = +-k (stable when the COM's foot is inside the face, |o_perp| < a); the side is the valley
// d.k = 0 (stable when |o.k| < b); the saddles between them are the die balanced on a rim point
// with the COM above it, at the distance from the COM to the nearest point of that rim circle.
// No impact or contact solve creates energy, so E < m g (that saddle's height) in a basin means
// the die ends in that basin. A face's basin is read at once; on its side the cylinder is also
// followed until it has stopped, so that `edge` is never read from a coin still rolling or
// spinning upright (a thin coin's side barrier is tens of um of lift).
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/dynamics/friction_impact.hpp"

namespace dicesim {

// Fills face_height, face_hold, face_escape, face_tip_ratio, face_gyro and face_area
// (max_escape: compute_escapes, rest.hpp).
void compute_rim_rest_geometry(DieModel& m);

// The quasi-static roll from orientation R: steepest descent of sigma on the sphere of down
// directions, in steps of 1e-3 rad (exact for an axisymmetric COM: the first step's side of the
// rim balance decides). Returns the face down (0, 1, 2) or -1 if the step guard ran out.
int rim_quasi_static_down(const DieModel& m, const Mat3& R, double tiebreak);

// The face the die must come to rest on (energy below its basin's saddle; on the side, also
// stopped: every point slower than 1e-3 sqrt(g r)), or -1; ke =
// kinetic_energy(m, s) (contact.hpp). (rest_face_down dispatches here for a curved die.)
int rim_rest_face_down(const DieModel& m, const RigidState& s, double tiebreak, double ke);

// Lowest contact-feature height relative to the COM (world z) over features not in c.
double rim_lowest_excluding(const DieModel& m, const Mat3& R, const ContactSet& c);

// Rolling resistance for one step with contact set c that carried normal impulse `normal_impulse`:
// an angular impulse rolling_resistance * normal_impulse against the roll (the angular velocity
// about the horizontal projection of the axis), capped so that it stops the roll at most (never
// reverses it: energy only falls). Tipping and pivoting are not resisted: resisting the tipping
// rate too (as this once did) held slowly rolling thin discs upright until they stopped.
void apply_rolling_resistance(const DieModel& m, RigidState& s, const ContactSet& c, double normal_impulse);

// Pivoting resistance for one step in which the die stands on one rim point (c.n == 1) that
// carried normal impulse `normal_impulse`: an angular impulse pivoting_resistance * normal_impulse
// about the floor's normal against the spin about it, capped so that it stops that spin at most
// (energy only falls: Delta K = lam (lam c / 2 - |w_z|) < 0, c = e_z . I_w^-1 e_z). A point
// contact has no torsional friction of its own; a real contact patch has, and without it a coin
// spinning upright on its rim never slowed (one toss spun 17 s, and the stepper's first-order
// error in that motion raised its held energy, counted as energy clamps: docs/fidelity.md).
// Two or more points (a cylinder on its side, a face's tripod) resist pivoting by their sliding
// friction already.
void apply_pivoting_resistance(const DieModel& m, RigidState& s, const ContactSet& c, double normal_impulse);

}  // namespace dicesim

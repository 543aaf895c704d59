// Coming to rest. The resting geometry of the die, the quasi-static roll to a face (the `static`
// model, and the basin test of the dynamic ones), and the rest criteria of `impulse` and `stepped`.
//
// The energy criterion is exact, not a threshold: h(R) = COM height of the die standing on the
// floor in orientation R has one minimum per (stable) face, and the lowest pass out of face A's
// basin is the die balanced on an edge of A with its COM straight above it (height face_escape[A]).
// No impact of these models creates energy and friction only removes it, so once
//   E = kinetic + m g (COM height + penetration)  <  m g face_escape[A]
// with the die in A's basin, it can never leave: it comes to rest on A, whatever it does next.
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/dynamics/flight.hpp"

namespace dicesim {

// Fills the face_* fields of a model whose vertices, face normals and frictions are set.
void compute_rest_geometry(DieModel& m);

// Quasi-static roll from orientation R (body -> world) standing on its lowest corner: pivot about
// that corner in the plane of steepest descent until an edge touches, tip about the edge toward the
// COM until a face touches, then over an edge while the face cannot hold the COM. Returns the face
// index (0..5) that ends down. `tiebreak` in [0, 1) decides exact balances (COM straight above the
// corner or the edge): derived from the toss index by the caller, never from hidden randomness.
int quasi_static_down_face(const DieModel& m, const Mat3& R, double tiebreak);

// The face (index) the die must come to rest on, or -1 while it is still undecided:
//  - energy: E < m g face_escape[A] with A = the basin of R (above); or
//  - lying flat: the four corners of A on the floor with vanishing normal velocity and every
//    corner's friction below face_tip_ratio[A], so friction cannot tip it while it slides/spins.
int rest_face_down(const DieModel& m, const RigidState& s, double tiebreak);

// The face opposite face index f (order +x, -x, +y, -y, +z, -z).
inline int opposite_face(int f) { return f ^ 1; }

}  // namespace dicesim

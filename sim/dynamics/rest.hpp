// Coming to rest. The resting geometry of the die, the quasi-static roll to a face (the `static`
// model, and the basin test of the dynamic ones), and the rest criteria of `impulse` and `stepped`.
//
// The energy criterion is exact, not a threshold: h(R) = COM height of the die standing on the
// floor in orientation R has one minimum per (stable) face, and the lowest pass out of face A's
// basin is the die balanced on an edge of A with its COM straight above it (height face_escape[A]).
// No impact of these models creates energy and friction only removes it, so once
//   E = kinetic + m g (COM height + penetration)  <  m g face_escape[A]
// with the die in A's basin, it can never leave: it comes to rest on A, whatever it does next.
// What a toss reports is the outcome, so the rule uses the pass out of the basins that read as A's
// outcome (outcome_escape, at least face_escape): below it the outcome is settled.
#pragma once

#include <cmath>

#include "sim/body/die_model.hpp"
#include "sim/dynamics/flight.hpp"

namespace dicesim {

// Fills the face_* fields but face_escape of a model whose vertices, faces (loops, normals,
// across), adjacency, frictions, rounding and principal moments are set.
void compute_rest_geometry(DieModel& m);

// Fills face_escape, outcome_escape and max_escape once the faces' reads are final (compile calls
// it after compute_rest_geometry and the read ties; for a cylinder after compute_rim_rest_geometry,
// whose face_escape it keeps). One pass over the saddles serves both: the die balanced on an edge
// with its COM straight above it (a critical point of the COM height only where the COM projects
// inside the edge and the vertical lies between the edge's two face normals), height = distance
// from the COM to the edge + rounding, separating the basins the two sides roll to.
// face_escape[B] is the lowest saddle on the boundary of B's basin. outcome_escape[A] is the lowest
// pass out of the region of basins that read as A's outcome: the least over paths of saddles from
// A's basin to a basin read as another outcome of the highest saddle on the path. Below it the die
// can wander between basins of its outcome (two triangles of one printed face, 1 degree apart,
// with a saddle 0.1 um above them) but never reach another outcome, so the outcome is settled.
// Where every neighbouring basin reads differently (every ready die but binom4) it equals
// face_escape; a cylinder's is its face_escape.
void compute_escapes(DieModel& m);

// Quasi-static roll from orientation R (body -> world) standing on its lowest corner: pivot about
// that corner in the vertical plane through it and the COM until an edge touches (steepest
// descent of the COM), then tip about the edge toward the COM until a face touches (or, if the COM
// projects beyond the edge's far end, pivot on that corner), then, while the face cannot hold the
// COM, over the edge (or pivot about the corner) of the face nearest the COM's foot. Returns the
// face index that ends down (always a face that holds the COM), or -1 if the roll did not end
// within its step guard (never seen; the caller counts it). `tiebreak` in [0, 1) decides exact
// balances (COM straight above the corner or the edge): derived from the toss index by the caller.
// Only the down direction R^T (-z) matters, so for a uniform orientation each face's probability
// is the area of its basin on the Gauss map over 4 pi.
int quasi_static_down_face(const DieModel& m, const Mat3& R, double tiebreak);

// The same roll starting with face f flat on the floor (f itself if it holds the COM).
int roll_from_face(const DieModel& m, int f, double tiebreak);

// The face (index) the die must come to rest on, or -1 while it is still undecided:
//  - energy: E < m g outcome_escape[A] with A = the basin of R (above): the die may still cross
//    into a basin of A's outcome, never into another's, so A is read; or
//  - lying flat: every corner of the face most nearly down, A, on the floor with vanishing normal
//    velocity; every corner's friction below face_tip_ratio[A], so friction cannot tip it while it
//    slides or spins; and the largest spin w about the vertical that the flat motion can ever
//    reach (all its kinetic energy in that spin, w^2 <= 2 KE / (n . I n)) small enough that the
//    torque keeping a non-principal axis upright, w^2 |n x I n|, is within what gravity holds,
//    m g face_hold[A] (beyond that the spinning die lifts an edge); the two together: friction's
//    and the spin's shifts of the centre of pressure, mu h and w^2 |n x I n| / (m g), add up to
//    less than face_hold[A]. A face that cannot hold the COM never qualifies. This one holds WHATEVER the kinetic energy (the die may slide at any speed):
//    lying flat, the contact forces that keep the face down exist and obey Coulomb's law. With c_i
//    the corners relative to the COM's foot, u_i their slip directions (any, for a sticking one)
//    and weights w_i = N_i / N >= 0 summing to 1, the horizontal torque about the COM vanishes
//    iff sum w_i (c_i - h mu u_i) = 0 (friction acts at the floor, depth h below the COM, so its
//    torque is h times the total friction, at most mu N h): the foot must lie in the convex hull
//    of the points c_i moved by at most mu h. The disc of radius face_hold around the foot lies in
//    the face, so the hull's support in every direction exceeds the foot's by at least
//    face_hold - mu h > 0: the foot is inside, nonnegative N_i exist, and no corner needs to
//    lift. The flat motion does no work against gravity and friction only removes kinetic
//    energy, so the spin bound holds ever after, and the die stops on A. (Until this revision a
//    cheap energy gate, E >= m g max_escape => undecided, ran first and also barred this rule: a
//    Die 1 `impulse` toss spent 11.6 of its 63 contact steps sliding flat on a face, already
//    decided. The gate now only ends the check when no corner can reach the floor either.)
int rest_face_down(const DieModel& m, const RigidState& s, double tiebreak);
// The same given ke = kinetic_energy(m, s) (contact.hpp), for a caller that has it already.
int rest_face_down(const DieModel& m, const RigidState& s, double tiebreak, double ke);

// The speed below which the rest rules count a corner (or, on a cylinder's side, the whole die) as
// still: 1e-3 sqrt(g r), r the bounding radius.
inline double rest_speed_tol(const DieModel& m) { return 1e-3 * std::sqrt(m.gravity * m.bounding_radius); }

// The face that is read when face f lies on the floor (the face up, or f for a die read down).
inline int result_face(const DieModel& m, int f) { return m.face_result[static_cast<std::size_t>(f)]; }

}  // namespace dicesim

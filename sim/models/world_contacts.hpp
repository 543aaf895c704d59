// A world toss's contacts (world_toss.cpp; internal to sim/models): what a pair of bodies is at
// one instant (its gap, normal and witness point by the narrow phase, or a lower bound), what the
// toss remembers of it between windows, where it touches (its contact patch) and how a die is
// struck against a fixed body there.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "sim/body/world.hpp"
#include "sim/dynamics/contact_patch.hpp"
#include "sim/dynamics/convex_distance.hpp"
#include "sim/dynamics/friction_impact.hpp"

namespace dicesim::world_detail {

inline constexpr int kMaxDice = 6;

// A contact between die i and something else at one instant.
struct Touch {
  double gap = 0.0;              // m, between the rounded surfaces (< 0: overlapping)
  Vec3 normal = Vec3::UnitZ();   // unit, from the other body into die i
  Vec3 point = Vec3::Zero();     // world, on die i's surface
  bool degenerate = false;
  bool exact = true;             // false: gap is only a lower bound (far apart), normal and point unset
};

PlacedHull placed(const World& w, int k, const RigidState& s);

PlacedHull placed(const ObstaclePiece& p);

// What a toss remembers of a pair between windows: the narrow phase's warm start, and its gap at
// the instants it was last measured at (for the next guess's secant). Direct-mapped by the pair
// (die i and die j, or die i and piece p, in that order): a slot is taken over by the last pair
// measured there.
struct PairMemo {
  SeparationCache sep;
  double gap = 0.0, at = -1.0;            // at the latest instant measured (at < 0: none, or touching)
  double prev_gap = 0.0, prev_at = -1.0;  // at the one before: an instant's later passes (after a
                                          // strike elsewhere) measure the pair again at the same at
  Vec3 axis = Vec3::Zero();     // the last exact touch's normal (zero: none)
  // The impulses of the pair's last strike at its patch's points (in the touch's frame), to start
  // the next strike's Gauss-Seidel sweeps from: a die lying on another or on an obstacle's top is
  // struck at the same points window after window.
  std::array<Vec3, 4> warm{};  // a patch has at most four points
  int warm_n = 0;
  // The last exact touch, and the stamps of the dice's places it was measured at (run_world's
  // stamps start at 1: 0, none; a piece's j stays 0).
  Touch touch;
  std::uint64_t measured_i = 0, measured_j = 0;
};

class PairMemos {
 public:
  PairMemo* die(int i, int j) { return slot((std::uint64_t(i) << 32) | std::uint64_t(j)); }
  PairMemo* piece(int i, std::size_t p) { return slot((std::uint64_t(i) << 32) | (std::uint64_t(p) + kMaxDice)); }

 private:
  static constexpr int kBits = 6;
  PairMemo* slot(std::uint64_t key) {
    const std::size_t k = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - kBits));
    if (keys_[k] != key + 1) {
      keys_[k] = key + 1;
      memos_[k] = PairMemo{};
    }
    return &memos_[k];
  }
  std::array<std::uint64_t, 1u << kBits> keys_{};  // 0: empty
  std::array<PairMemo, 1u << kBits> memos_{};
};

// The most fixed bodies (obstacles, dice at rest) one die's held_still weighs, besides the floor.
inline constexpr int kMaxHolds = 4;

// One fixed body's touch of a die (an obstacle, a die at rest, the floor), for held_still: the
// points of its patch, its normal (into the die) and the friction coefficient there.
struct HeldTouch {
  ContactPatch patch;
  Vec3 normal = Vec3::UnitZ();
  double mu = 0.0;
};

// Whether forces at these touches, within their friction cones, can hold die d at s against
// gravity: a static equilibrium. Tested as the plastic strike of a die given gravity's kick over
// tau, from rest, at every point at once (projected Gauss-Seidel over the points, each in its own
// normal's frame, up to kHeldSweeps sweeps): it minimises the kinetic energy over the impulses the
// cones allow, so it stops the die when, and only when, such forces exist. Held: the die's points
// end slower than 1e-6 g tau, an unbalanced acceleration under 1e-6 g (over the half second a
// still die is otherwise watched, under 1.3 um of motion). Not held: the residual stalls (falls
// less than 1 % in ten sweeps; where no such forces exist the sweeps converge to a die that still
// moves), or is not met within kHeldSweeps (at worst a hold missed: the die is watched as before).
// (Held dice converge geometrically: one wedged between a die and a pyramid's overhang, its residual
// falling 0.7 in ten sweeps, took 370.)
bool held_still(const DieModel& d, const RigidState& s, std::span<const HeldTouch> touches, double tau);
inline constexpr int kHeldSweeps = 2000;

// The die's corners within `within` of the floor, as a touch for held_still (n = 0: none).
HeldTouch floor_touch(const DieModel& d, const RigidState& s, double within);

// The velocity of the rigid motion s at world point x.
Vec3 point_velocity(const RigidState& s, const Vec3& x);

// A lower bound on the gap between two bodies from any unit axis n (from b toward a): how far
// a's corners lie beyond b's along it, less the roundings. At the last normal of a pair that has
// moved a little, it is nearly the gap itself, for a few dot products instead of GJK.
double axis_gap(std::span<const Vec3> a, double ra, std::span<const Vec3> b, double rb, const Vec3& n);

Touch touch_piece(const World& w, int k, const RigidState& s, const ObstaclePiece& p, SeparationCache* cache = nullptr);

Touch touch_die(const World& w, int i, const RigidState& si, int j, const RigidState& sj,
                SeparationCache* cache = nullptr);

// A pair this far apart (a lower bound) is not measured exactly: the bound is the gap.
Touch far_apart(double gap);

// Frame turning n to +z (the floor law's normal), as a rotation matrix.
Mat3 to_normal_frame(const Vec3& n);

// Where die i (its corners `mine`, world) touches a piece at `t` (contact_patch.hpp), within tol;
// the witness point if the patch came out empty (`*witness_only` counts it). The piece's surface
// plane at the touch is n . x = n . point - gap.
ContactPatch piece_patch(const DieModel& d, std::span<const Vec3> mine, const ObstaclePiece& p, const Touch& t,
                         double tol, std::uint64_t* witness_only);

// Where dice i and j (their corners, world) touch at `t` (t.point lies midway between their
// surfaces); the witness point if the patch came out empty, counted.
ContactPatch dice_patch(const DieModel& di, std::span<const Vec3> ci, const DieModel& dj, std::span<const Vec3> cj,
                        const Touch& t, double tol, std::uint64_t* witness_only);

// The least normal velocity of die i relative to the other body (its velocity and spin; zero for
// a fixed one) over a patch's points: under -v_still, the pair approaches.
double patch_approach(const ContactPatch& patch, const RigidState& si, const RigidState* sj, const Vec3& n,
                      int* fastest = nullptr);

// Die i against a fixed body (an obstacle, or a die held at rest) over a contact patch: the floor's
// law turned to the touch's normal, every point of the patch together. `d` carries the pair's
// materials. If the patch's solve leaves the witness point approaching (by more than 1e-10 of the
// speeds involved, the floor law's allowance for rounding), that point is struck on its own too
// (counted in `witness`).
ImpactResult strike_fixed(const DieModel& d, RigidState& s, const Touch& t, const ContactPatch& patch,
                          bool restitution, std::uint64_t& witness, PairMemo& memo);

// A die's world inverse inertia at orientation R.
Mat3 inverse_inertia(const DieModel& d, const Mat3& R);

}  // namespace dicesim::world_detail

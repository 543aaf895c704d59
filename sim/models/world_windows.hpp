// A world toss's windows (world_toss.cpp; internal to sim/models): how fast a die can close a gap,
// by its points and by its bounding sphere, for the rest of the toss and along its exact flight,
// and so how long a pair's gap surely stays open.
#pragma once

#include <span>

#include "sim/body/die_model.hpp"
#include "sim/models/impulse_run.hpp"
#include "sim/models/toss.hpp"

namespace dicesim::world_detail {

// How fast die k's points can move, two ways:
//  * for the rest of the toss: sqrt(2 E / m) + r sqrt(2 E / I_min) (world_toss.cpp says why), with
//    5 % spare for the stepper's rounding-level gains;
//  * while it flies, until its next floor contact (found exactly, as its own flight finds it):
//    the COM's velocity v + g t, and the spin's part at most r sqrt(2 K_rot / I_min) (K_rot is
//    constant in flight).
// Pairs take the longer of the two windows each bound allows.
struct Reach {
  double any = 0.0;       // the whole-toss bound (m/s); 0: at rest (only others strike it)
  double com = 0.0;       // the whole-toss bound on the COM's speed, sqrt(2 E / m) (m/s)
  bool flying = false;    // in flight now (not in the stepper's hands)
  double free_for = 0.0;  // flying: how long it stays clear of the floor at least (s)
  Vec3 v = Vec3::Zero();  // flying: the COM's velocity now
  double spin = 0.0;      // flying: the spin's bound on a point's speed relative to the COM
};

// Die r's reach now (zero: at rest). A run about to fly starts its flight here (its rest check first).
Reach reach_of(ImpulseRun& r, TossProbe* probe);

// The longest window in which points approaching at `closing` + accel t (m/s) cannot close `gap`
// (closing < 0: moving apart, until accel turns them; accel >= 0).
double window_for(double gap, double closing, double accel);

// Bounding spheres: a die stays inside the sphere of its bounding radius about its COM however it
// spins, so a sphere's gap closes only as fast as the COMs move. Each window below is how long a
// sphere gap `gap` surely stays open:
//  * for the rest of the toss, at the COM's energy bound (Reach::com);
//  * while the dice fly (until the first one's next floor contact), along their exact COM motion,
//    then at the energy bound for what is left.
// Two flying dice: gravity moves both COMs alike, so their relative position d + v t is a straight
// line; the window is when it first comes within R (the radii's sum) of zero.
double spheres_window(const Reach& a, const Reach& b, const Vec3& d, double R);

// A flying die's sphere against a fixed surface `gap` away along unit n (pointing into the die;
// n = 0: direction unknown, any): its COM closes at v(t) . (-n) <= v_in + g_in t until the floor
// contact, then at the energy bound.
double sphere_fixed_window(const Reach& a, double gap, const Vec3& n, double g);

// How soon a corner of the die (at s, its corners placed in the world: `corners`) would reach the
// plane {x : n . x = level} (n pointing into the die) at its velocity now relative to the other
// body there (`other`'s rigid motion at the corner's place; none: a fixed body): min over corners
// of height / approach (+inf if none approaches). A far corner approaching fast does not shorten
// it as a near one does.
double closing_time(const DieModel& d, std::span<const Vec3> corners, const RigidState& s, const Vec3& n, double level,
                    const RigidState* other);

}  // namespace dicesim::world_detail

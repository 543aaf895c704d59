// A toss's initial state, drawn from the scene's throw distributions by (seed, toss index).
#pragma once

#include <cstdint>

#include "sim/math.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

struct InitialState {
  Vec3 com_position = Vec3::Zero();  // world (m); x, y = 0, z = COM height
  Vec3 velocity = Vec3::Zero();      // world (m/s)
  Mat3 orientation = Mat3::Identity();  // geometric frame -> world
  Vec3 omega = Vec3::Zero();         // world angular velocity (rad/s)
  double catch_time = 0.0;           // sim.end = "catch": when the hand catches the die (s)
};

// Draws in a fixed order (orientation, height, velocity, spin, then the catch time if the throw has
// one) from TossRandom(seed, toss). `motion` false stops after the height (velocity, spin and catch
// time stay zero): what `static` reads, the same orientation and height as the full draw, at a
// quarter of its cost.
InitialState draw_initial_state(const ThrowDef& thr, std::uint64_t seed, std::uint64_t toss, bool motion = true);

// Orientation helpers (exposed for tests).
Mat3 uniform_rotation(double u1, double u2, double u3);  // Shoemake: Haar measure on SO(3)
Vec3 uniform_unit_vector(double u1, double u2);

}  // namespace dicesim

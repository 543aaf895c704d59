// Random rotations and directions for the narrow-phase tests (fixed-seed generators only).
#pragma once

#include <random>

#include "sim/math.hpp"

namespace dicesim::testing {

// Uniform over rotations: a normalised quaternion of four normal deviates.
inline Mat3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
}

// Uniform over the unit sphere.
inline Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

}  // namespace dicesim::testing

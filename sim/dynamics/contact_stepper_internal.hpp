// Internal to FixedStepper's source files (contact_stepper.cpp, stepper_trial.cpp, rim_step.cpp, rim_support.cpp): helpers they
// share. Not part of the public interface (contact_stepper.hpp); include it nowhere else.
#pragma once

#include <algorithm>
#include <cmath>

#include "sim/body/die_model.hpp"
#include "sim/dynamics/contact.hpp"

namespace dicesim::stepper_detail {

inline double mechanical_energy(const DieModel& m, const RigidState& s) {
  return kinetic_energy(m, s) + m.mass * m.gravity * s.position.z();
}

// World height, relative to the COM, of the lowest point of rim `rim` (0: the +axis rim, 1: the
// other) from the orientation's bottom row (rim.hpp's rim_point for feature 3 rim, in closed form).
inline double rim_low_z(const DieModel& m, const Vec3& z_row, int rim) {
  const double kz = z_row.dot(m.rims.axis);
  return z_row.dot(m.rims.centre) + (rim == 0 ? m.rims.half : -m.rims.half) * kz -
         m.rims.radius * std::sqrt(std::max(0.0, 1.0 - kz * kz)) - m.rounding;
}

}  // namespace dicesim::stepper_detail

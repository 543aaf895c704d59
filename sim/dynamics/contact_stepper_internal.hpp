// Internal to FixedStepper's source files (contact_stepper.cpp, stepper_trial.cpp): helpers they
// share. Not part of the public interface (contact_stepper.hpp); include it nowhere else.
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/dynamics/contact.hpp"

namespace dicesim::stepper_detail {

inline double mechanical_energy(const DieModel& m, const RigidState& s) {
  return kinetic_energy(m, s) + m.mass * m.gravity * s.position.z();
}

}  // namespace dicesim::stepper_detail

// key_unit: the unit of a numeric scene key, read from the ranges the scene reader checks (key_unit.hpp).
#include "sim/scene/key_unit.hpp"

#include "sim/scene/scene_reader.hpp"

namespace dicesim {

using namespace scene_detail;

std::string key_unit(std::string_view key) {
  // The key without indices, and any material's name as "*": "materials.*.density".
  std::string k;
  for (std::size_t i = 0; i < key.size(); ++i) {
    if (key[i] == '[') {
      while (i < key.size() && key[i] != ']') ++i;
      continue;
    }
    k += key[i];
  }
  if (k.rfind("materials.", 0) == 0) {
    const std::size_t dot = k.find('.', 10);
    if (dot != std::string::npos) k = "materials.*" + k.substr(dot);
  }
  static const std::pair<std::string_view, const Range*> units[] = {
      {"materials.*.density", &kDensity},
      {"materials.*.rolling_resistance", &kRollingResistance},
      {"materials.*.pivoting_resistance", &kPivotingResistance},
      {"die.size", &kEdge},
      {"die.radius", &kEdge},
      {"die.length", &kEdge},
      {"die.height", &kEdge},
      {"die.rounding", &kRounding},
      {"die.regions.cuts.offset", &kLength},
      {"throw.orientation.euler_deg", &kAngle},
      {"throw.height.mean", &kLength},
      {"throw.height.sd", &kLengthSd},
      {"throw.velocity.mean", &kSpeed},
      {"throw.velocity.sd", &kSpeedSd},
      {"throw.spin.mean", &kSpin},
      {"throw.spin.sd", &kSpinSd},
      {"throw.spin.tilt_deg", &kAngle},
      {"throw.spin.tilt_sd_deg", &kTiltSd},
      {"throw.catch_time.mean", &kCatchTime},
      {"throw.catch_time.sd", &kCatchTimeSd},
      {"sim.gravity", &kGravity},
      {"sim.stop_speed", &kStopSpeed},
      {"sim.max_time", &kMaxTime},
      {"sim.step", &kStep},
      {"sim.contact_step", &kStep},
      {"sim.contact_tol", &kContactTol},
      {"dice.offset", &kOffset},
      {"obstacles.point", &kPosition},
      {"obstacles.vertices", &kPosition},
      {"obstacles.centre", &kPosition},
      {"obstacles.size", &kEdge},
      {"obstacles.yaw_deg", &kYaw},
      {"obstacles.thickness", &kEdge},
      {"obstacles.width", &kEdge},
      {"obstacles.height", &kEdge},
      {"obstacles.radius", &kEdge},
      {"obstacles.pyramid_base", &kEdge},
      {"obstacles.pyramid_height", &kEdge},
      {"obstacles.pyramid_pitch", &kEdge},
      {"obstacles.baffle_angle_deg", &kBaffleAngle},
      {"obstacles.exit_height", &kEdge},
  };
  for (const auto& [name, range] : units)
    if (k == name) return range->unit;
  return "";
}

}  // namespace dicesim

// `static`: random orientation, then the quasi-static roll to the resting face.
#include <algorithm>
#include <cmath>

#include "sim/models/fidelity_models.hpp"
#include "sim/dynamics/rest.hpp"

namespace dicesim {

TossResult run_static(const DieModel& m, const RigidState& s, double tiebreak) {
  TossResult r;
  const int down = quasi_static_down_face(m, s.R, tiebreak);
  if (down < 0) {  // the roll's step guard (never seen): counted as unresolved, not guessed
    r.status = TossStatus::Unresolved;
    return r;
  }
  set_result_face(m, result_face(m, down), r);
  r.status = TossStatus::Settled;
  return r;
}

std::vector<double> static_face_probabilities(const DieModel& m, int directions) {
  std::vector<double> p(static_cast<std::size_t>(m.face_count()), 0.0);
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  int counted = 0;
  for (int i = 0; i < directions; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / directions;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const Vec3 down(rho * std::cos(golden * i), rho * std::sin(golden * i), z);  // body frame
    const Mat3 R = Eigen::Quaterniond::FromTwoVectors(down, -Vec3::UnitZ()).toRotationMatrix();
    const int f = quasi_static_down_face(m, R, 0.5);
    if (f < 0) continue;
    p[static_cast<std::size_t>(result_face(m, f))] += 1.0;
    ++counted;
  }
  for (double& x : p) x /= std::max(1, counted);
  return p;
}

}  // namespace dicesim

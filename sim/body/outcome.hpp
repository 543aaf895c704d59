// Reading the result: the face whose outward normal points most nearly up.
#pragma once

#include "sim/body/die_model.hpp"

namespace dicesim {

// Index (0..5, order +x, -x, +y, -y, +z, -z of the geometric frame) of the face most aligned
// with +z for body->world rotation R. Ties go to the lower index (deterministic).
inline int top_face_index(const DieModel& m, const Mat3& R) {
  int best = 0;
  double best_z = -2.0;
  for (int f = 0; f < 6; ++f) {
    const double z = R.row(2).dot(m.face_normals[f]);
    if (z > best_z) {
      best_z = z;
      best = f;
    }
  }
  return best;
}

}  // namespace dicesim

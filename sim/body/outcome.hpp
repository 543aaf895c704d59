// Reading the result: the face whose outward normal points most nearly up (or, for a die read
// from below such as a d4, most nearly down), and the outcome (label) it shows.
#pragma once

#include "sim/body/die_model.hpp"

namespace dicesim {

// Index of the face most aligned with +z (read_down: with -z) for body->world rotation R.
// Ties go to the lower index (deterministic).
inline int read_face_index(const DieModel& m, const Mat3& R) {
  if (m.curved()) {  // heads (0), tails (1), or the side (2): whose outward normal is most nearly up
    const double kz = R.row(2).dot(m.rims.axis);
    if (kz * kz >= 0.5) return kz > 0.0 ? 0 : 1;
    return 2;
  }
  int best = 0;
  double best_z = -2.0;
  const double sign = m.read_down ? -1.0 : 1.0;
  const int n = m.face_count();
  for (int f = 0; f < n; ++f) {
    const double z = sign * R.row(2).dot(m.face_normals[static_cast<std::size_t>(f)]);
    if (z > best_z) {
      best_z = z;
      best = f;
    }
  }
  return best;
}

// The face most nearly up when caught in the hand: a face, never the side (a cylinder: heads 0 or
// tails 1; a polytope: as read_face_index).
inline int caught_face_index(const DieModel& m, const Mat3& R) {
  if (m.curved()) return R.row(2).dot(m.rims.axis) >= 0.0 ? 0 : 1;
  return read_face_index(m, R);
}

}  // namespace dicesim

// Reading the result: the face whose outward normal points most nearly up (or, for a die read
// from below such as a d4, most nearly down), and the outcome (label) it shows.
#pragma once

#include <string>
#include <vector>

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

// Per outcome (outcome_labels order), a coin's side names: "heads", "tails", "edge", joined by "/"
// when labels group them. Empty for a die (its outcomes are its face labels).
inline std::vector<std::string> outcome_names(const DieModel& m) {
  std::vector<std::string> names;
  if (!m.curved()) return names;
  names.assign(m.outcome_labels.size(), "");
  for (std::size_t f = 0; f < m.face_outcome.size() && f < kCylinderOutcomeNames.size(); ++f) {
    std::string& name = names[static_cast<std::size_t>(m.face_outcome[f])];
    if (!name.empty()) name += '/';
    name += kCylinderOutcomeNames[f];
  }
  return names;
}

}  // namespace dicesim

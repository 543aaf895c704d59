// Reading the result: the face whose outward normal points most nearly up (or, for a die read
// from below such as a d4, most nearly down), and the outcome (label) it shows.
#pragma once

#include <string>
#include <vector>

#include "sim/body/die_model.hpp"

namespace dicesim {

// Index of the face most aligned with +z (read_down: with -z) for body->world rotation R; a die
// lying on a face that is read as its own (DieModel::own_read_faces) reads that face. Exact ties
// (measure zero) go to the lower index.
inline int read_face_index(const DieModel& m, const Mat3& R) {
  if (m.curved()) {  // heads (0), tails (1), or the side (2): whose outward normal is most nearly up
    const double kz = R.row(2).dot(m.rims.axis);
    if (kz * kz >= 0.5) return kz > 0.0 ? 0 : 1;
    return 2;
  }
  if (!m.own_read_faces.empty() && !m.read_down) {
    int down = 0;
    double down_z = 2.0;
    for (int f = 0; f < m.face_count(); ++f)
      if (const double z = R.row(2).dot(m.face_normals[static_cast<std::size_t>(f)]); z < down_z) {
        down_z = z;
        down = f;
      }
    if (m.face_result[static_cast<std::size_t>(down)] == down) return down;
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

// The label read when the die rests on face f (the face up, the face down, or f's own label:
// DieModel::own_read_faces).
inline int resting_outcome_label(const DieModel& m, int f) {
  const int g = m.face_result[static_cast<std::size_t>(f)];
  return m.outcome_labels[static_cast<std::size_t>(m.face_outcome[static_cast<std::size_t>(g)])];
}

// The classes of two or more outcomes alike by design (DieModel::outcome_alike), as labels.
inline std::vector<std::vector<int>> alike_groups(const DieModel& m) {
  std::vector<std::vector<int>> groups;
  for (std::size_t first = 0; first < m.outcome_alike.size(); ++first) {
    if (m.outcome_alike[first] != static_cast<int>(first)) continue;
    std::vector<int> g;
    for (std::size_t k = first; k < m.outcome_alike.size(); ++k)
      if (m.outcome_alike[k] == static_cast<int>(first)) g.push_back(m.outcome_labels[k]);
    if (g.size() > 1) groups.push_back(std::move(g));
  }
  return groups;
}

}  // namespace dicesim

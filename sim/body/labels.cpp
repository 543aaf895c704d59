#include "sim/body/labels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "sim/scene/scene_error.hpp"

namespace dicesim {
namespace {

std::string vec_text(const Vec3& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "[%.6g, %.6g, %.6g]", v.x(), v.y(), v.z());
  return buf;
}

// Opposite faces sum to `sum`; labels first, first + 1, ... in face order.
std::vector<int> opposite_pairs(const ConvexShape& s, int first, int sum) {
  std::vector<int> labels(s.faces.size(), -1);
  int next = first;
  for (std::size_t f = 0; f < s.faces.size(); ++f) {
    if (labels[f] >= 0) continue;
    labels[f] = next;
    const int o = nearest_face(s, -s.normals[f]);
    if (o != static_cast<int>(f) && labels[o] < 0) labels[o] = sum - next;
    ++next;
  }
  return labels;
}

}  // namespace

int nearest_face(const ConvexShape& s, const Vec3& direction) {
  const Vec3 d = direction.normalized();
  int best = 0;
  double best_cos = -2.0;
  for (std::size_t f = 0; f < s.normals.size(); ++f)
    if (const double c = s.normals[f].dot(d); c > best_cos) {
      best_cos = c;
      best = static_cast<int>(f);
    }
  return best;
}

std::vector<int> face_labels(const ConvexShape& s, const DieDef& die, const std::string& origin) {
  const int n = static_cast<int>(s.faces.size());
  std::vector<int> labels(n);
  switch (die.shape) {
    case ShapeKind::Box:
    case ShapeKind::D6:
      // By direction: a rounded box's core is listed in the canonical order, not +x, -x, ...
      for (int f = 0; f < n; ++f) {
        const Vec3& m = s.normals[f];
        int axis = 0;
        m.cwiseAbs().maxCoeff(&axis);
        labels[f] = die.face_labels[2 * axis + (m[axis] > 0.0 ? 0 : 1)];
      }
      break;
    case ShapeKind::D8:
    case ShapeKind::D12:
    case ShapeKind::D20:
      labels = opposite_pairs(s, 1, n + 1);
      break;
    case ShapeKind::D10:
      labels = opposite_pairs(s, 0, 9);
      break;
    case ShapeKind::Prism: {
      const double pi = std::acos(-1.0);
      for (int f = 0; f < n; ++f) {
        const Vec3& m = s.normals[f];
        if (std::abs(m.z()) > 0.5) {
          labels[f] = die.sides + (m.z() > 0.0 ? 1 : 2);
        } else {
          double a = std::atan2(m.y(), m.x());
          if (a < -1e-9) a += 2.0 * pi;
          labels[f] = static_cast<int>(std::lround(a * die.sides / (2.0 * pi))) % die.sides + 1;
        }
      }
      break;
    }
    default:  // d4, hull, mesh
      for (int f = 0; f < n; ++f) labels[f] = f + 1;
  }

  std::vector<int> named_by(n, -1);
  for (std::size_t i = 0; i < die.labels.size(); ++i) {
    const int f = nearest_face(s, die.labels[i].normal);
    if (named_by[f] >= 0)
      throw SceneError(origin, "die.labels[" + std::to_string(i) + "].normal", vec_text(die.labels[i].normal),
                       "names the same face (outward normal " + vec_text(s.normals[f]) + ") as die.labels[" +
                           std::to_string(named_by[f]) + "]; each face takes at most one label");
    named_by[f] = static_cast<int>(i);
    labels[f] = die.labels[i].label;
  }
  if (!die.labels.empty() && (die.shape == ShapeKind::Hull || die.shape == ShapeKind::Mesh)) {
    std::set<int> used;
    for (const LabelDef& l : die.labels) used.insert(l.label);
    int next = 1;
    for (int f = 0; f < n; ++f) {
      if (named_by[f] >= 0) continue;
      while (used.count(next)) ++next;
      labels[f] = next++;
    }
  }
  return labels;
}

}  // namespace dicesim

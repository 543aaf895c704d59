#include "sim/body/presets.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "sim/body/hull.hpp"

namespace dicesim {
namespace {

constexpr double kPhi = 1.6180339887498948482;  // golden ratio

// Corners of each regular die at an arbitrary scale; the hull gives faces and normals.
std::vector<Vec3> preset_corners(ShapeKind kind) {
  std::vector<Vec3> p;
  switch (kind) {
    case ShapeKind::D4:
      p = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
      break;
    case ShapeKind::D8:
      for (int a = 0; a < 3; ++a)
        for (double s : {1.0, -1.0}) {
          Vec3 v = Vec3::Zero();
          v[a] = s;
          p.push_back(v);
        }
      break;
    case ShapeKind::D12:
      for (double x : {1.0, -1.0})
        for (double y : {1.0, -1.0})
          for (double z : {1.0, -1.0}) p.emplace_back(x, y, z);
      for (double s : {1.0, -1.0})
        for (double t : {1.0, -1.0}) {
          p.emplace_back(0.0, s / kPhi, t * kPhi);
          p.emplace_back(s / kPhi, t * kPhi, 0.0);
          p.emplace_back(t * kPhi, 0.0, s / kPhi);
        }
      break;
    case ShapeKind::D20:
      for (double s : {1.0, -1.0})
        for (double t : {1.0, -1.0}) {
          p.emplace_back(0.0, s, t * kPhi);
          p.emplace_back(s, t * kPhi, 0.0);
          p.emplace_back(t * kPhi, 0.0, s);
        }
      break;
    case ShapeKind::D10: {
      // Face planes n.x = 1 with n = (c cos a, c sin a, +-s), c = 2/sqrt5, s = 1/sqrt5. A ring corner
      // at azimuth b lies on the upper faces at b -+ 36 deg and the lower face at b:
      //   c rho cos36 + s z = 1 and c rho - s z = 1  =>  rho = 2 / (c (1 + cos36)), z = (c rho - 1) / s.
      const double c = 2.0 / std::sqrt(5.0), s = 1.0 / std::sqrt(5.0);
      const double deg = std::acos(-1.0) / 180.0;
      const double rho = 2.0 / (c * (1.0 + std::cos(36.0 * deg)));
      const double z = (c * rho - 1.0) / s;
      p = {{0, 0, 1.0 / s}, {0, 0, -1.0 / s}};
      for (int k = 0; k < 5; ++k) {
        const double up = (36.0 + 72.0 * k) * deg, down = 72.0 * k * deg;
        p.emplace_back(rho * std::cos(up), rho * std::sin(up), z);
        p.emplace_back(rho * std::cos(down), rho * std::sin(down), -z);
      }
      break;
    }
    default:
      throw std::invalid_argument("preset_shape: not a preset with corners");
  }
  return p;
}

}  // namespace

double min_face_distance(const ConvexShape& s) {
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < s.faces.size(); ++f) d = std::min(d, s.normals[f].dot(s.vertices[s.faces[f][0]]));
  return d;
}

ConvexShape preset_shape(ShapeKind kind, double size) {
  if (kind == ShapeKind::D6) return box_shape(Vec3::Constant(size));
  ConvexShape s = convex_hull(preset_corners(kind));
  // Scale so that opposite faces are `size` apart (d4: face to vertex = 4 x inradius).
  const double target = kind == ShapeKind::D4 ? size / 4.0 : size / 2.0;
  const double k = target / min_face_distance(s);
  for (Vec3& v : s.vertices) v *= k;
  return s;
}

ConvexShape prism_shape(int sides, double radius, double length) {
  if (sides < 3) throw std::invalid_argument("prism_shape: needs at least 3 sides");
  const double pi = std::acos(-1.0);
  std::vector<Vec3> p;
  for (int k = 0; k < sides; ++k) {
    const double a = 2.0 * pi * (k + 0.5) / sides;
    for (double z : {0.5 * length, -0.5 * length}) p.emplace_back(radius * std::cos(a), radius * std::sin(a), z);
  }
  return convex_hull(p);
}

}  // namespace dicesim

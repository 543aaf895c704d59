// Convex dice built in code for the polytope tests (no scene keys needed): the convex hull of a
// few points by brute force (every supporting plane of three points; coplanar points merge into
// one face), exact mass properties of a uniform polytope by tetrahedra from an interior point,
// and a Body ready for compile_body(). Small inputs only (O(n^4)).
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "sim/body/body.hpp"
#include "sim/math.hpp"

namespace dicesim::testing {

// Faces of the hull of `pts` (all of which must be corners), counter-clockwise from outside.
inline ConvexShape hull_shape(const std::vector<Vec3>& pts) {
  ConvexShape s;
  s.vertices = pts;
  const int n = static_cast<int>(pts.size());
  double scale = 0.0;
  for (const Vec3& p : pts) scale = std::max(scale, p.norm());
  const double eps = 1e-9 * scale;
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : pts) centre += p / n;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      for (int k = j + 1; k < n; ++k) {
        Vec3 nrm = (pts[j] - pts[i]).cross(pts[k] - pts[i]);
        if (nrm.norm() <= 1e-12 * scale * scale) continue;
        nrm.normalize();
        double d = nrm.dot(pts[i]);
        if (nrm.dot(centre) > d) {
          nrm = -nrm;
          d = -d;
        }
        bool support = true;
        std::vector<int> on;
        for (int q = 0; q < n && support; ++q) {
          const double z = nrm.dot(pts[q]) - d;
          if (z > eps) support = false;
          if (std::abs(z) <= eps) on.push_back(q);
        }
        if (!support) continue;
        bool seen = false;
        for (const Vec3& m : s.normals) seen = seen || (m - nrm).norm() < 1e-9;
        if (seen) continue;
        // Order the face's corners counter-clockwise about the outward normal.
        Vec3 c = Vec3::Zero();
        for (int q : on) c += pts[q] / static_cast<double>(on.size());
        const Vec3 u = (pts[on[0]] - c).normalized(), w = nrm.cross(u);
        std::sort(on.begin(), on.end(), [&](int a, int b) {
          return std::atan2((pts[a] - c).dot(w), (pts[a] - c).dot(u)) < std::atan2((pts[b] - c).dot(w), (pts[b] - c).dot(u));
        });
        s.faces.push_back(on);
        s.normals.push_back(nrm);
      }
  return s;
}

// Volume integrals of the polytope (unit density) about the origin, by tetrahedra from `apex`.
inline void add_moments(const ConvexShape& s, double density, double& mass, Vec3& first, Mat3& second) {
  Vec3 apex = Vec3::Zero();
  for (const Vec3& v : s.vertices) apex += v / static_cast<double>(s.vertices.size());
  for (const auto& loop : s.faces)
    for (std::size_t t = 1; t + 1 < loop.size(); ++t) {
      const Vec3 a = apex, b = s.vertices[static_cast<std::size_t>(loop[0])], c = s.vertices[static_cast<std::size_t>(loop[t])],
                 d = s.vertices[static_cast<std::size_t>(loop[t + 1])];
      const double vol = std::abs((b - a).dot((c - a).cross(d - a))) / 6.0;
      const Vec3 sum = a + b + c + d;
      mass += density * vol;
      first += density * vol * sum / 4.0;
      // Integral of x x^T over a tetrahedron: vol/20 (sum_i v_i v_i^T + sum_{ij} v_i v_j^T).
      const Vec3 vs[4] = {a, b, c, d};
      Mat3 S = sum * sum.transpose();
      for (const Vec3& v : vs) S += v * v.transpose();
      second += density * vol / 20.0 * S;
    }
}

inline MassProperties mass_from_moments(double mass, const Vec3& first, const Mat3& second) {
  MassProperties mp;
  mp.mass = mass;
  mp.com = first / mass;
  const Mat3 S = second - mass * mp.com * mp.com.transpose();  // about the COM
  mp.inertia = S.trace() * Mat3::Identity() - S;
  const Eigen::SelfAdjointEigenSolver<Mat3> es(mp.inertia);
  mp.principal_moments = es.eigenvalues();
  mp.principal_axes = es.eigenvectors();
  if (mp.principal_axes.determinant() < 0.0) mp.principal_axes.col(2) *= -1.0;
  return mp;
}

// A uniform die of `density` on the hull of `pts`; labels 1..F in face order; plastic corners.
inline Body hull_body(const std::vector<Vec3>& pts, double density = 1200.0, const std::string& kind = "hull") {
  Body b;
  b.kind = kind;
  b.shape = hull_shape(pts);
  for (std::size_t f = 0; f < b.shape.faces.size(); ++f) b.face_labels.push_back(static_cast<int>(f) + 1);
  double mass = 0.0;
  Vec3 first = Vec3::Zero();
  Mat3 second = Mat3::Zero();
  add_moments(b.shape, density, mass, first, second);
  b.mass = mass_from_moments(mass, first, second);
  b.vertex_restitution.assign(pts.size(), 0.5);
  b.vertex_friction.assign(pts.size(), 0.3);
  return b;
}

// Adds a dense slab under face f: the frustum between the face and its copy scaled by (1 - depth)
// toward the origin (inside the die by convexity), of extra density `extra`.
inline void load_face(Body& b, std::size_t f, double depth, double extra) {
  std::vector<Vec3> slab;
  for (int v : b.shape.faces[f]) {
    slab.push_back(b.shape.vertices[static_cast<std::size_t>(v)]);
    slab.push_back((1.0 - depth) * b.shape.vertices[static_cast<std::size_t>(v)]);
  }
  double mass = b.mass.mass;
  Vec3 first = mass * b.mass.com;
  const Mat3 S_com = 0.5 * b.mass.inertia.trace() * Mat3::Identity() - b.mass.inertia;
  Mat3 second = S_com + mass * b.mass.com * b.mass.com.transpose();
  add_moments(hull_shape(slab), extra, mass, first, second);
  b.mass = mass_from_moments(mass, first, second);
}

inline double golden() { return 0.5 * (1.0 + std::sqrt(5.0)); }

// Regular solids with circumradius `r` (about 15 mm for a game die).
inline std::vector<Vec3> tetrahedron(double r = 0.015) {
  const double k = r / std::sqrt(3.0);
  return {Vec3(k, k, k), Vec3(k, -k, -k), Vec3(-k, k, -k), Vec3(-k, -k, k)};
}
inline std::vector<Vec3> cube(double r = 0.015) {
  std::vector<Vec3> v;
  const double k = r / std::sqrt(3.0);
  for (int c = 0; c < 8; ++c) v.emplace_back((c & 1) ? k : -k, (c & 2) ? k : -k, (c & 4) ? k : -k);
  return v;
}
inline std::vector<Vec3> octahedron(double r = 0.015) {
  return {Vec3(r, 0, 0), Vec3(-r, 0, 0), Vec3(0, r, 0), Vec3(0, -r, 0), Vec3(0, 0, r), Vec3(0, 0, -r)};
}
inline std::vector<Vec3> icosahedron(double r = 0.015) {
  const double p = golden(), k = r / std::sqrt(1.0 + p * p);
  std::vector<Vec3> v;
  for (int a = -1; a <= 1; a += 2)
    for (int b = -1; b <= 1; b += 2) {
      v.emplace_back(0.0, a * k, b * p * k);
      v.emplace_back(a * k, b * p * k, 0.0);
      v.emplace_back(b * p * k, 0.0, a * k);
    }
  return v;
}
// A regular n-gon prism: circumradius `radius` of the n-gon, `length` along z.
inline std::vector<Vec3> prism(int n, double radius, double length) {
  std::vector<Vec3> v;
  for (int z = 0; z < 2; ++z)
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * kPi * i / n;
      v.emplace_back(radius * std::cos(a), radius * std::sin(a), (z ? 0.5 : -0.5) * length);
    }
  return v;
}
// An irregular hull: 9 points in general position (every face a triangle, unequal basins).
inline std::vector<Vec3> irregular(double s = 0.015) {
  return {s * Vec3(1.0, 0.1, -0.2),   s * Vec3(-0.8, 0.6, 0.1),  s * Vec3(0.2, -1.1, 0.3),
          s * Vec3(-0.3, -0.4, 1.2),  s * Vec3(0.1, 0.3, -0.9),  s * Vec3(0.7, 0.8, 0.5),
          s * Vec3(-0.6, -0.7, -0.5), s * Vec3(0.5, -0.2, 0.9),  s * Vec3(-0.2, 1.0, -0.4)};
}

}  // namespace dicesim::testing

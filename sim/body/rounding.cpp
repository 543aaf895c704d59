// Closed forms for the curved pieces of a rounded die.
//
// Edge wedge, local coordinates y = (s, rho cos phi, rho sin phi) in the frame Q = [e, u, w] at a,
// volume element rho drho dphi ds, s in [0, L], rho in [0, r], phi in [0, t]:
//   V = L t r^2 / 2
//   int y = (L^2/2 t r^2/2, L r^3/3 sin t, L r^3/3 (1 - cos t))
//   int y y^T: ss = L^3/3 t r^2/2; s y2 = L^2/2 r^3/3 sin t; s y3 = L^2/2 r^3/3 (1 - cos t);
//              y2 y2 = L r^4/4 (t/2 + sin 2t/4); y3 y3 = L r^4/4 (t/2 - sin 2t/4); y2 y3 = L r^4/4 sin^2 t / 2
// and x = a + Q y.
//
// Corner sector over the spherical polygon A of the face normals at corner p (the corner's
// normal cone), x = p + rho n, volume element rho^2 drho dOmega:
//   int 1 = r^3/3 Omega,  int x = p r^3/3 Omega + r^4/4 M1,  int x x^T = p p^T r^3/3 Omega
//   + r^4/4 (p M1^T + M1 p^T) + r^5/5 M2,   M1 = int_A n dOmega,  M2 = int_A n n^T dOmega.
// Omega = 2 pi - (sum of the face angles at p) (Gauss-Bonnet: A's turning angle at each face
// normal is that face's angle at p). M1 and M2 by Green's theorem on the sphere: n_i is a degree-1
// spherical harmonic (Laplace-Beltrami L n_i = -2 n_i) and n_i n_j - delta_ij/3 a degree-2 one
// (L = -6), so, with nu the outward conormal of A's boundary,
//   M1 = -1/2 oint nu ds,   M2 = Omega/3 I - 1/6 oint (nu n^T + n nu^T) ds.
// A's sides are great arcs between the normals n1, n2 of the two faces at an edge of the corner;
// their plane is perpendicular to that edge, and the outward conormal is the edge's direction e
// away from p (the normal cone lies where n.e <= 0). Along the arc of angle t:
//   int ds = t,  int n ds = (n1 + n2) tan(t/2).
// Hence M1 = -1/2 sum t e,  M2 = Omega/3 I - 1/6 sum (e c^T + c e^T), c = (n1 + n2) tan(t/2).
#include "sim/body/rounding.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "sim/body/hull.hpp"

namespace dicesim {
namespace {


double angle_between(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

void add_moments(VolumeMoments& total, const VolumeMoments& part) { accumulate(total, part, 1.0); }

Triangles slab(const ConvexShape& core, std::size_t f, double r) {
  const auto& loop = core.faces[f];
  const Vec3 up = r * core.normals[f];
  Triangles t;
  const Vec3& a0 = core.vertices[loop[0]];
  for (std::size_t k = 1; k + 1 < loop.size(); ++k) {
    const Vec3& b = core.vertices[loop[k]];
    const Vec3& c = core.vertices[loop[k + 1]];
    t.push_back({a0 + up, b + up, c + up});  // top, counter-clockwise about +n
    t.push_back({a0, c, b});                 // bottom, facing -n
  }
  for (std::size_t k = 0; k < loop.size(); ++k) {
    const Vec3& a = core.vertices[loop[k]];
    const Vec3& b = core.vertices[loop[(k + 1) % loop.size()]];
    t.push_back({a, b, b + up});
    t.push_back({a, b + up, a + up});
  }
  return t;
}

}  // namespace

VolumeMoments edge_wedge_moments(const Vec3& a, const Vec3& b, const Vec3& u, const Vec3& v, double r) {
  const double length = (b - a).norm();
  const Vec3 e = (b - a) / length;
  const double t = angle_between(u, v);
  VolumeMoments m;
  if (!(t > 0.0) || !(length > 0.0)) return m;
  const Vec3 w = (v - std::cos(t) * u).normalized();
  const double L = length, r2 = r * r, r3 = r2 * r, r4 = r3 * r;
  const double st = std::sin(t), ct = std::cos(t);
  const double volume = L * t * r2 / 2.0;
  const Vec3 fy(L * L / 2.0 * t * r2 / 2.0, L * r3 / 3.0 * st, L * r3 / 3.0 * (1.0 - ct));
  Mat3 sy;
  sy(0, 0) = L * L * L / 3.0 * t * r2 / 2.0;
  sy(0, 1) = sy(1, 0) = L * L / 2.0 * r3 / 3.0 * st;
  sy(0, 2) = sy(2, 0) = L * L / 2.0 * r3 / 3.0 * (1.0 - ct);
  sy(1, 1) = L * r4 / 4.0 * (t / 2.0 + std::sin(2.0 * t) / 4.0);
  sy(2, 2) = L * r4 / 4.0 * (t / 2.0 - std::sin(2.0 * t) / 4.0);
  sy(1, 2) = sy(2, 1) = L * r4 / 4.0 * st * st / 2.0;
  Mat3 q;
  q.col(0) = e;
  q.col(1) = u;
  q.col(2) = w;
  const Vec3 qf = q * fy;
  m.volume = volume;
  m.first = volume * a + qf;
  m.second = volume * a * a.transpose() + a * qf.transpose() + qf * a.transpose() + q * sy * q.transpose();
  return m;
}

VolumeMoments corner_sector_moments(const Vec3& p, double sum_face_angles, const std::vector<CornerEdge>& edges,
                                    double r) {
  const double omega = 2.0 * kPi - sum_face_angles;
  Vec3 m1 = Vec3::Zero();
  Mat3 m2 = (omega / 3.0) * Mat3::Identity();
  for (const CornerEdge& e : edges) {
    const double t = angle_between(e.n1, e.n2);
    const Vec3 c = (e.n1 + e.n2) * std::tan(t / 2.0);
    m1 -= 0.5 * t * e.direction;
    m2 -= (e.direction * c.transpose() + c * e.direction.transpose()) / 6.0;
  }
  const double r3 = r * r * r, r4 = r3 * r, r5 = r4 * r;
  VolumeMoments m;
  m.volume = r3 / 3.0 * omega;
  m.first = p * m.volume + r4 / 4.0 * m1;
  m.second = m.volume * p * p.transpose() + r4 / 4.0 * (p * m1.transpose() + m1 * p.transpose()) + r5 / 5.0 * m2;
  return m;
}

RoundedSolid::RoundedSolid(const ConvexShape& core, double r) : r_(r) {
  core_ = shape_triangles(core);
  double area = 0.0, edge_term = 0.0;
  for (std::size_t f = 0; f < core.faces.size(); ++f) {
    slabs_.push_back(slab(core, f, r));
    area += face_area(core, f);
  }
  // Directed edge -> face; each undirected edge once (a < b).
  std::map<std::pair<int, int>, int> owner;
  for (std::size_t f = 0; f < core.faces.size(); ++f) {
    const auto& loop = core.faces[f];
    for (std::size_t k = 0; k < loop.size(); ++k) owner[{loop[k], loop[(k + 1) % loop.size()]}] = static_cast<int>(f);
  }
  std::vector<double> angle_sum(core.vertices.size(), 0.0);
  std::vector<std::vector<CornerEdge>> corner_edges(core.vertices.size());
  for (std::size_t f = 0; f < core.faces.size(); ++f) {
    const auto& loop = core.faces[f];
    const std::size_t n = loop.size();
    for (std::size_t k = 0; k < n; ++k) {
      const int prev = loop[(k + n - 1) % n], v = loop[k], next = loop[(k + 1) % n];
      angle_sum[v] += angle_between(core.vertices[prev] - core.vertices[v], core.vertices[next] - core.vertices[v]);
      if (v > next) continue;
      const auto other = owner.find({next, v});
      if (other == owner.end()) continue;
      const Vec3& a = core.vertices[v];
      const Vec3& b = core.vertices[next];
      const Vec3& n1 = core.normals[f];
      const Vec3& n2 = core.normals[other->second];
      edge_term += edge_wedge_moments(a, b, n1, n2, r).volume;
      wedges_.push_back({a, b, n1, n2});
      const Vec3 e = (b - a).normalized();
      corner_edges[v].push_back({e, n1, n2});
      corner_edges[next].push_back({-e, n1, n2});
    }
  }
  for (std::size_t v = 0; v < core.vertices.size(); ++v) {
    corners_.push_back(corner_sector_moments(core.vertices[v], angle_sum[v], corner_edges[v], r));
  }
  double core_volume = surface_moments(core_).volume;
  steiner_volume_ = core_volume + area * r + edge_term + 4.0 / 3.0 * kPi * r * r * r;
}

VolumeMoments RoundedSolid::moments(const std::vector<HalfSpace>& cuts) const {
  VolumeMoments m = clipped_surface_moments(core_, cuts);
  for (const Triangles& s : slabs_) add_moments(m, clipped_surface_moments(s, cuts));
  auto keeps = [&](const VolumeMoments& piece, bool skip_parallel_to_edge, const Vec3& edge) {
    if (!(piece.volume > 0.0)) return false;
    const Vec3 centroid = piece.first / piece.volume;
    for (const HalfSpace& c : cuts) {
      if (skip_parallel_to_edge && std::abs(c.normal.normalized().dot(edge)) >= 1.0 - 1e-12) continue;
      if (c.normal.dot(centroid) > c.offset) return false;
    }
    return true;
  };
  for (const Wedge& w : wedges_) {
    const double length = (w.b - w.a).norm();
    const Vec3 e = (w.b - w.a) / length;
    double s0 = 0.0, s1 = length;
    for (const HalfSpace& c : cuts) {
      const double along = c.normal.dot(e);
      if (std::abs(along) < (1.0 - 1e-12) * c.normal.norm()) continue;
      const double bound = (c.offset - c.normal.dot(w.a)) / along;  // c.normal.(a + s e) <= offset
      if (along > 0.0)
        s1 = std::min(s1, bound);
      else
        s0 = std::max(s0, bound);
    }
    if (!(s1 > s0)) continue;
    const VolumeMoments piece = edge_wedge_moments(w.a + s0 * e, w.a + s1 * e, w.n1, w.n2, r_);
    if (keeps(piece, true, e)) add_moments(m, piece);
  }
  for (const VolumeMoments& c : corners_)
    if (keeps(c, false, Vec3::Zero())) add_moments(m, c);
  return m;
}

ConvexShape shrink_shape(const ConvexShape& outer, double r) {
  std::vector<HalfSpace> planes;
  for (std::size_t f = 0; f < outer.faces.size(); ++f)
    planes.push_back({outer.normals[f], outer.normals[f].dot(outer.vertices[outer.faces[f][0]]) - r});
  const Triangles t = clipped_surface(shape_triangles(outer), planes);
  if (t.empty()) throw HullError("nothing is left of the die");
  std::vector<Vec3> points;
  for (const auto& tri : t) points.insert(points.end(), tri.begin(), tri.end());
  // Many points repeat (shared corners): drop exact repeats to keep the hull cheap.
  std::sort(points.begin(), points.end(), [](const Vec3& a, const Vec3& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  ConvexShape core = convex_hull(points);
  core.rounding = r;
  return core;
}

double inradius(const ConvexShape& outer) {
  double lo = 0.0, hi = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < outer.faces.size(); ++f) {
    double min_d = std::numeric_limits<double>::infinity();
    const double d = outer.normals[f].dot(outer.vertices[outer.faces[f][0]]);
    for (const Vec3& v : outer.vertices) min_d = std::min(min_d, outer.normals[f].dot(v));
    hi = std::min(hi, 0.5 * (d - min_d));  // half the width across this face
  }
  // Something solid is left of the shrunk die exactly while r is below the inradius.
  const Triangles surface = shape_triangles(outer);
  for (int i = 0; i < 80 && hi - lo > 1e-10 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    std::vector<HalfSpace> planes;
    for (std::size_t f = 0; f < outer.faces.size(); ++f)
      planes.push_back({outer.normals[f], outer.normals[f].dot(outer.vertices[outer.faces[f][0]]) - mid});
    (clipped_surface_moments(surface, planes).volume > 0.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace dicesim

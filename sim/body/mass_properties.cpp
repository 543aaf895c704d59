#include "sim/body/mass_properties.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace dicesim {
namespace {

// A convex polyhedron as its faces; each face lists its vertices counter-clockwise seen from
// outside, so that the divergence theorem (tetrahedra to an interior point) gives positive volumes.
using Polygon = std::vector<Vec3>;
using Polyhedron = std::vector<Polygon>;

Polyhedron make_box(const Vec3& lo, const Vec3& hi) {
  // Corner i has bit k set <=> it is on the `hi` side along axis k.
  auto corner = [&](int i) {
    return Vec3((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
  };
  static constexpr int kFaces[6][4] = {
      {1, 3, 7, 5},  // +x
      {0, 4, 6, 2},  // -x
      {2, 6, 7, 3},  // +y
      {0, 1, 5, 4},  // -y
      {4, 5, 7, 6},  // +z
      {0, 2, 3, 1},  // -z
  };
  Polyhedron box;
  for (const auto& face : kFaces) box.push_back({corner(face[0]), corner(face[1]), corner(face[2]), corner(face[3])});
  return box;
}

void check_cut(const HalfSpace& cut) {
  if (!cut.normal.allFinite() || !std::isfinite(cut.offset))
    throw std::invalid_argument("mass properties: a cut has a non-finite normal or offset");
  if (cut.normal.squaredNorm() == 0.0)
    throw std::invalid_argument("mass properties: a cut has a zero normal, which defines no plane");
}

// The cap closing a clipped polyhedron: its points lie on the plane and form a convex polygon.
// Ordering them by angle about their centroid, counter-clockwise about the unit normal `n`, makes
// the cap face outwards (the kept side is n.x <= d, so the outside is along +n).
Polygon order_cap(const Polygon& points, const Vec3& n, double tol) {
  Polygon unique;
  for (const Vec3& p : points) {
    const bool seen = std::any_of(unique.begin(), unique.end(), [&](const Vec3& q) { return (p - q).norm() <= tol; });
    if (!seen) unique.push_back(p);
  }
  if (unique.size() < 3) return {};
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : unique) centroid += p;
  centroid /= static_cast<double>(unique.size());
  const Vec3 u = n.unitOrthogonal();
  const Vec3 v = n.cross(u);  // (u, v, n) right-handed
  std::vector<std::pair<double, Vec3>> by_angle;
  for (const Vec3& p : unique) by_angle.emplace_back(std::atan2((p - centroid).dot(v), (p - centroid).dot(u)), p);
  std::sort(by_angle.begin(), by_angle.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  Polygon cap;
  for (const auto& [angle, p] : by_angle) cap.push_back(p);
  return cap;
}

// Keeps the part of `poly` where n.x <= d (n unit). Vertices within `tol` of the plane count as on
// it, so a plane through existing vertices, edges or faces adds no slivers or duplicate points.
Polyhedron clip(const Polyhedron& poly, const Vec3& n, double d, double tol) {
  auto distance = [&](const Vec3& p) { return n.dot(p) - d; };
  bool any_outside = false, any_inside = false;
  for (const Polygon& face : poly)
    for (const Vec3& p : face) {
      any_outside = any_outside || distance(p) > tol;
      any_inside = any_inside || distance(p) < -tol;
    }
  // Nothing strictly outside: the plane misses or only touches (this also makes a repeated,
  // coplanar cut a no-op). Nothing strictly inside: at most a face or edge is left, volume 0.
  if (!any_outside) return poly;
  if (!any_inside) return {};

  Polyhedron kept_faces;
  Polygon cap_points;
  for (const Polygon& face : poly) {
    Polygon kept;
    for (std::size_t i = 0; i < face.size(); ++i) {
      const Vec3& a = face[i];
      const Vec3& b = face[(i + 1) % face.size()];
      const double sa = distance(a), sb = distance(b);
      if (sa <= tol) kept.push_back(a);
      if (std::abs(sa) <= tol) cap_points.push_back(a);
      if ((sa < -tol && sb > tol) || (sa > tol && sb < -tol)) {
        // Interpolate from the inside end so that the two faces sharing this edge compute the
        // bit-identical point (the edge is walked in opposite directions by its two faces).
        const bool a_inside = sa < 0.0;
        const Vec3& in = a_inside ? a : b;
        const Vec3& out = a_inside ? b : a;
        const double s_in = a_inside ? sa : sb, s_out = a_inside ? sb : sa;
        const Vec3 crossing = in + (out - in) * (s_in / (s_in - s_out));
        kept.push_back(crossing);
        cap_points.push_back(crossing);
      }
    }
    if (kept.size() >= 3) kept_faces.push_back(std::move(kept));
  }
  Polygon cap = order_cap(cap_points, n, tol);
  if (!cap.empty()) kept_faces.push_back(std::move(cap));
  return kept_faces;
}

// Exact integrals over the tetrahedron (a, b, c, d), signed by orientation:
//   V = det[b-a, c-a, d-a] / 6,  int x dV = V s / 4,  int x x^T dV = V/20 (sum v v^T + s s^T),
// with s = a + b + c + d.
void add_tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, VolumeMoments& m) {
  const double volume = (b - a).dot((c - a).cross(d - a)) / 6.0;
  const Vec3 s = a + b + c + d;
  m.volume += volume;
  m.first += (volume / 4.0) * s;
  m.second += (volume / 20.0) *
              (a * a.transpose() + b * b.transpose() + c * c.transpose() + d * d.transpose() + s * s.transpose());
}

// Divergence theorem on a closed, outward-oriented convex polyhedron: fan each face into
// triangles and join each to an interior point (the vertex mean).
VolumeMoments integrate(const Polyhedron& poly) {
  VolumeMoments m;
  Vec3 apex = Vec3::Zero();
  std::size_t count = 0;
  for (const Polygon& face : poly) {
    for (const Vec3& p : face) apex += p;
    count += face.size();
  }
  if (count == 0) return m;
  apex /= static_cast<double>(count);
  for (const Polygon& face : poly)
    for (std::size_t i = 1; i + 1 < face.size(); ++i) add_tetrahedron(apex, face[0], face[i], face[i + 1], m);
  return m;
}


// Principal moments (ascending) and axes (columns, right-handed), chosen deterministically.
// The solver's eigenvectors for a repeated moment are an arbitrary basis of its eigenspace, so
// for each group of equal moments (within 1e-12 of the largest) we build the basis ourselves:
// take the geometric axis whose projection onto the eigenspace is longest (ties, within 1e-9,
// go to the lower index), Gram-Schmidt it against the axes already chosen, repeat. Hence
//   - a tensor diagonal in the geometric frame gets geometric axes (homogeneous cube: identity;
//     a z-slab die: x, y, z);
//   - every axis points to the positive side of the geometric axis it is closest to.
// The moments of a group are replaced by their mean (they agree to rounding). If the frame comes
// out left-handed, the two axes of a doubly repeated moment are swapped (both remain eigenvectors
// pointing to positive sides); without such a pair the third axis is negated (the one exception
// to the sign rule above).
void principal_frame(const Mat3& inertia, Vec3& moments, Mat3& axes) {
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(inertia);
  if (solver.info() != Eigen::Success) throw std::runtime_error("mass properties: eigen-decomposition failed");
  moments = solver.eigenvalues();
  const Mat3& vectors = solver.eigenvectors();
  const double same = 1e-12 * moments.cwiseAbs().maxCoeff();
  int pair_begin = -1;  // first column of a doubly repeated moment, if any
  for (int begin = 0, end = 0; begin < 3; begin = end) {
    end = begin + 1;
    while (end < 3 && moments(end) - moments(begin) <= same) ++end;
    const int size = end - begin;
    if (size == 2) pair_begin = begin;
    moments.segment(begin, size).setConstant(moments.segment(begin, size).mean());
    const Mat3 projector = size == 3 ? Mat3::Identity()
                                     : Mat3(vectors.middleCols(begin, size) * vectors.middleCols(begin, size).transpose());
    for (int col = begin; col < end; ++col) {
      Vec3 best = Vec3::Zero();
      for (int k = 0; k < 3; ++k) {
        Vec3 candidate = projector.col(k);
        for (int prev = begin; prev < col; ++prev) candidate -= axes.col(prev).dot(candidate) * axes.col(prev);
        if (candidate.norm() > best.norm() + 1e-9) best = candidate;
      }
      axes.col(col) = best.normalized();
    }
  }
  if (axes.determinant() < 0.0) {
    if (pair_begin >= 0)
      axes.col(pair_begin).swap(axes.col(pair_begin + 1));
    else
      axes.col(2) = -axes.col(2);
  }
}

// Keeps the part of a closed triangle surface where n.x <= d and closes it again. Each triangle is
// clipped to a convex polygon (fanned back into triangles); every polygon edge that lies on the
// plane is a piece of the cut's outline, and the outline pieces of all polygons, reversed, fanned
// from one point on the plane, form the cap. Edges on the plane shared by two kept polygons come
// in opposite directions and cancel in the fan, so the cap is right for any closed surface.
Triangles clip_surface(const Triangles& in, const Vec3& n, double d, double tol) {
  bool any_outside = false, any_inside = false;
  for (const auto& t : in)
    for (const Vec3& p : t) {
      const double s = n.dot(p) - d;
      any_outside = any_outside || s > tol;
      any_inside = any_inside || s < -tol;
    }
  if (!any_outside) return in;
  if (!any_inside) return {};
  Triangles out;
  std::vector<std::pair<Vec3, Vec3>> outline;
  for (const auto& t : in) {
    std::array<Vec3, 4> poly;
    std::array<bool, 4> on{};
    int m = 0;
    for (int i = 0; i < 3; ++i) {
      const Vec3& a = t[i];
      const Vec3& b = t[(i + 1) % 3];
      const double sa = n.dot(a) - d, sb = n.dot(b) - d;
      if (sa <= tol) {
        poly[m] = a;
        on[m++] = std::abs(sa) <= tol;
      }
      if ((sa < -tol && sb > tol) || (sa > tol && sb < -tol)) {
        // From the inside end: the two triangles sharing this edge get the bit-identical point.
        const bool a_inside = sa < 0.0;
        const Vec3& pin = a_inside ? a : b;
        const Vec3& pout = a_inside ? b : a;
        const double s_in = a_inside ? sa : sb, s_out = a_inside ? sb : sa;
        poly[m] = pin + (pout - pin) * (s_in / (s_in - s_out));
        on[m++] = true;
      }
    }
    if (m < 3) continue;
    for (int i = 1; i + 1 < m; ++i) out.push_back({poly[0], poly[i], poly[i + 1]});
    for (int i = 0; i < m; ++i)
      if (on[i] && on[(i + 1) % m]) outline.emplace_back(poly[i], poly[(i + 1) % m]);
  }
  if (!outline.empty()) {
    const Vec3 q = outline.front().first;
    for (const auto& [a, b] : outline) out.push_back({q, b, a});
  }
  return out;
}

}  // namespace

void accumulate(VolumeMoments& total, const VolumeMoments& part, double weight) {
  total.volume += weight * part.volume;
  total.first += weight * part.first;
  total.second += weight * part.second;
}

VolumeMoments surface_moments(const Triangles& surface) {
  VolumeMoments m;
  if (surface.empty()) return m;
  Vec3 apex = Vec3::Zero();
  for (const auto& t : surface) apex += t[0] + t[1] + t[2];
  apex /= static_cast<double>(3 * surface.size());
  for (const auto& t : surface) add_tetrahedron(apex, t[0], t[1], t[2], m);
  return m;
}

Triangles clipped_surface(const Triangles& surface, const std::vector<HalfSpace>& cuts) {
  for (const HalfSpace& cut : cuts) check_cut(cut);
  if (surface.empty()) return {};
  Vec3 lo = surface[0][0], hi = lo;
  for (const auto& t : surface)
    for (const Vec3& p : t) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  const double size = (hi - lo).norm();
  const double reach = lo.cwiseAbs().cwiseMax(hi.cwiseAbs()).norm();
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  Triangles clipped = surface;
  for (const HalfSpace& cut : cuts) {
    const double length = cut.normal.norm();
    const double offset = cut.offset / length;
    const double tol = 1e-12 * size + 8.0 * kEps * (reach + std::abs(offset));
    clipped = clip_surface(clipped, cut.normal / length, offset, tol);
    if (clipped.empty()) return {};
  }
  return clipped;
}

VolumeMoments clipped_surface_moments(const Triangles& surface, const std::vector<HalfSpace>& cuts) {
  return surface_moments(clipped_surface(surface, cuts));
}

VolumeMoments clipped_aabb_moments(const Vec3& lo, const Vec3& hi, const std::vector<HalfSpace>& cuts) {
  if (!lo.allFinite() || !hi.allFinite() || (hi - lo).minCoeff() < 0.0)
    throw std::invalid_argument("mass properties: the box needs finite corners with lo <= hi");
  for (const HalfSpace& cut : cuts) check_cut(cut);
  if ((hi - lo).minCoeff() == 0.0) return {};

  // A vertex counts as on a plane within 1e-12 of the box's size, plus the rounding error of
  // evaluating n.x - d where coordinates are large against the box (a small box at a die corner).
  const double size = (hi - lo).norm();
  const double reach = lo.cwiseAbs().cwiseMax(hi.cwiseAbs()).norm();
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  Polyhedron poly = make_box(lo, hi);
  for (const HalfSpace& cut : cuts) {
    const double length = cut.normal.norm();
    const double offset = cut.offset / length;
    const double tol = 1e-12 * size + 8.0 * kEps * (reach + std::abs(offset));
    poly = clip(poly, cut.normal / length, offset, tol);
    if (poly.empty()) return {};
  }
  return integrate(poly);
}

VolumeMoments clipped_box_moments(const Vec3& size, const std::vector<HalfSpace>& cuts) {
  return clipped_aabb_moments(-0.5 * size, 0.5 * size, cuts);
}

Mat3 inertia_from_second_moment(const Mat3& second, double density) {
  return density * (second.trace() * Mat3::Identity() - second);
}

MassProperties compute_mass_properties(const DieDef& die, const std::map<std::string, MaterialDef>& materials) {
  // Base density over the whole box, then each region corrects it to its own density. Exact
  // because regions do not overlap. Unknown material names throw std::out_of_range (map::at).
  const double base_density = materials.at(die.base_material).density;
  VolumeMoments mass_moments;  // density-weighted: mass, int rho x dV, int rho x x^T dV
  accumulate(mass_moments, clipped_box_moments(die.size, {}), base_density);
  for (const RegionDef& region : die.regions)
    accumulate(mass_moments, clipped_box_moments(die.size, region.half_spaces),
               materials.at(region.material).density - base_density);

  return mass_properties_from_moments(mass_moments);
}

MassProperties mass_properties_from_moments(const VolumeMoments& mass_moments) {
  MassProperties mp;
  mp.mass = mass_moments.volume;
  // No mass (a zero-size die): nothing else is defined. Report the mass alone and leave the rest at
  // its defaults; the caller rejects it with a message naming the scene key (sim/body/body.cpp).
  if (!(mp.mass > 0.0) || !std::isfinite(mp.mass)) return mp;
  mp.com = mass_moments.first / mp.mass;
  // Parallel-axis theorem on the second moment, then I = tr(S) 1 - S (already density-weighted).
  const Mat3 second_about_com = mass_moments.second - mp.mass * mp.com * mp.com.transpose();
  const Mat3 inertia = inertia_from_second_moment(second_about_com, 1.0);
  mp.inertia = 0.5 * (inertia + inertia.transpose());
  principal_frame(mp.inertia, mp.principal_moments, mp.principal_axes);
  return mp;
}

}  // namespace dicesim

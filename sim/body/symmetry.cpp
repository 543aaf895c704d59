#include "sim/body/symmetry.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "sim/body/mesh.hpp"

namespace dicesim {
namespace {

constexpr double kRel = 1e-7;          // matching tolerance, relative to the die's size
constexpr int kSamples = 4096;         // material probes
constexpr std::size_t kMaxCorners = 400;

double halton(int i, int base) {
  double f = 1.0, r = 0.0;
  for (; i > 0; i /= base) {
    f /= base;
    r += f * (i % base);
  }
  return r;
}

bool same_material(const MaterialDef* a, const MaterialDef* b) {
  if (!a || !b) return a == b;
  return a->density == b->density && a->restitution == b->restitution && a->friction == b->friction &&
         a->rolling_resistance == b->rolling_resistance && a->pivoting_resistance == b->pivoting_resistance;
}

// Ray parity (a fixed, generic direction): inside a closed surface, convex or not.
bool inside_surface(const Triangles& tris, const Vec3& p) {
  const Vec3 d = Vec3(0.2718281828, 0.5772156649, 0.7701319089).normalized();
  int crossings = 0;
  for (const auto& t : tris) {
    const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
    const Vec3 h = d.cross(e2);
    const double det = e1.dot(h);
    if (std::abs(det) < 1e-300) continue;
    const Vec3 s = p - t[0];
    const double u = s.dot(h) / det;
    if (u < 0.0 || u > 1.0) continue;
    const Vec3 q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (v < 0.0 || u + v > 1.0) continue;
    if (e2.dot(q) / det > 0.0) ++crossings;
  }
  return crossings % 2 == 1;
}

// The material at a point of the geometric frame (nullptr: outside a non-convex mesh's solid).
struct Layout {
  const DieDef& die;
  const std::map<std::string, MaterialDef>& materials;
  const Triangles* solid = nullptr;
  const MaterialDef* at(const Vec3& p) const {
    if (solid && !inside_surface(*solid, p)) return nullptr;
    for (const RegionDef& r : die.regions) {
      bool in = true;
      for (const HalfSpace& h : r.half_spaces) in = in && h.normal.dot(p) <= h.offset;
      if (in) return &materials.at(r.material);
    }
    return &materials.at(die.base_material);
  }
};

class Checker {
 public:
  Checker(const Body& body, const SceneDef& scene, double size, std::vector<Vec3> probes, const Triangles* solid)
      : body_(body), layout_{scene.die, scene.materials, solid}, size_(size), probes_(std::move(probes)) {
    for (const Vec3& p : probes_) probe_material_.push_back(layout_.at(p));
  }
  // The inertia tensor and the material at every probe are carried onto themselves by S.
  bool keeps_mass(const Mat3& S) const {
    const Mat3& I = body_.mass.inertia;
    if ((S * I * S.transpose() - I).norm() > kRel * I.norm()) return false;
    const Vec3& c = body_.mass.com;
    for (std::size_t i = 0; i < probes_.size(); ++i)
      if (!same_material(probe_material_[i], layout_.at(c + S * (probes_[i] - c)))) return false;
    return true;
  }
  double size() const { return size_; }

 private:
  const Body& body_;
  Layout layout_;
  double size_;
  std::vector<Vec3> probes_;
  std::vector<const MaterialDef*> probe_material_;
};

std::vector<Vec3> box_probes(const Vec3& lo, const Vec3& hi, const auto& inside) {
  std::vector<Vec3> probes;
  for (int i = 1; static_cast<int>(probes.size()) < kSamples && i < 8 * kSamples; ++i) {
    const Vec3 p = lo + (hi - lo).cwiseProduct(Vec3(halton(i, 2), halton(i, 3), halton(i, 5)));
    if (inside(p)) probes.push_back(p);
  }
  return probes;
}

std::string count_text(std::size_t n) { return std::to_string(n) + (n == 1 ? " rotation" : " rotations"); }

DieSymmetry cylinder_symmetry(const Body& body, const SceneDef& scene) {
  DieSymmetry sym;
  sym.rotations.push_back(Mat3::Identity());
  const CylinderShape& c = body.cylinder;
  const double size = std::max(c.radius, 0.5 * c.height);
  if (body.mass.com.norm() > kRel * size) {
    sym.note = "the centre of mass is off the coin's centre, so no rotation turns it over onto itself";
    return sym;
  }
  for (int k = 0; k < 3; ++k)
    if (body.vertex_restitution[k] != body.vertex_restitution[k + 3] || body.vertex_friction[k] != body.vertex_friction[k + 3] ||
        body.vertex_rolling[k] != body.vertex_rolling[k + 3] || body.vertex_pivoting[k] != body.vertex_pivoting[k + 3]) {
      sym.note = "its two rims are of different materials, so no rotation turns it over onto itself";
      return sym;
    }
  auto inside = [&](const Vec3& p) { return std::hypot(p.x(), p.y()) <= c.radius && std::abs(p.z()) <= 0.5 * c.height; };
  const Checker check(body, scene, size, box_probes(Vec3(-c.radius, -c.radius, -0.5 * c.height),
                                                    Vec3(c.radius, c.radius, 0.5 * c.height), inside), nullptr);
  // Turning it over: a half turn about a diameter (every half degree of azimuth is tried; first the
  // axis of a spin about a body axis, the only diameter whose half turn keeps that spin).
  std::vector<Vec3> diameters;
  const Vec3 spin = scene.throw_.spin.axis;
  if (scene.throw_.spin.kind == SpinKind::BodyAxis && std::abs(spin.z()) <= 1e-12 * spin.norm())
    diameters.push_back(spin.normalized());
  for (int k = 0; k < 360; ++k) diameters.emplace_back(std::cos(kPi * k / 360.0), std::sin(kPi * k / 360.0), 0.0);
  for (const Vec3& u : diameters) {
    const Mat3 S = 2.0 * u * u.transpose() - Mat3::Identity();
    if (check.keeps_mass(S)) {
      sym.rotations.push_back(S);
      sym.note = "a half turn about a diameter carries the coin (shape and materials) onto itself";
      return sym;
    }
  }
  sym.note = "no half turn about a diameter carries its materials onto themselves";
  return sym;
}

DieSymmetry polytope_symmetry(const Body& body, const SceneDef& scene) {
  DieSymmetry sym;
  sym.rotations.push_back(Mat3::Identity());
  const ConvexShape& s = body.shape;
  const std::size_t n = s.vertices.size();
  if (n > kMaxCorners) {
    sym.note = "over " + std::to_string(kMaxCorners) + " corners: its symmetry was not looked for";
    return sym;
  }
  const Vec3 com = body.mass.com;
  std::vector<Vec3> P;
  double size = 0.0;
  for (const Vec3& v : s.vertices) {
    P.push_back(v - com);
    size = std::max(size, P.back().norm());
  }
  const double tol = kRel * size;

  // Probes inside the hull; a mesh that is not convex also tells its solid from its hollows.
  Triangles solid;
  std::vector<Vec3> mesh_points;
  if (!body.convex) {
    const ObjMesh mesh = parse_obj(scene.die.mesh_text, scene.die.mesh_path);
    solid = mesh_triangles(mesh, scene.die.scale);
    for (const Vec3& v : used_vertices(mesh, scene.die.scale)) mesh_points.push_back(v - com);
  }
  Vec3 lo = s.vertices.front(), hi = lo;
  for (const Vec3& v : s.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  auto inside = [&](const Vec3& p) {
    for (std::size_t f = 0; f < s.faces.size(); ++f)
      if (s.normals[f].dot(p - s.vertices[static_cast<std::size_t>(s.faces[f].front())]) > 0.0) return false;
    return true;
  };
  const Checker check(body, scene, size, box_probes(lo, hi, inside), body.convex ? nullptr : &solid);

  auto maps_onto = [&](const Mat3& S, const std::vector<Vec3>& pts, bool materials) {
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const Vec3 q = S * pts[i];
      std::size_t j = 0;
      while (j < pts.size() && (pts[j] - q).norm() > tol) ++j;
      if (j == pts.size()) return false;
      if (materials && (body.vertex_restitution[i] != body.vertex_restitution[j] || body.vertex_friction[i] != body.vertex_friction[j]))
        return false;
    }
    return true;
  };

  // Reference corners: a of the rarest distance from the COM, b the farthest off a's line.
  auto same_norm = [&](const Vec3& x, const Vec3& y) { return std::abs(x.norm() - y.norm()) <= tol; };
  std::size_t a = 0, a_count = n + 1;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<std::size_t>(std::count_if(P.begin(), P.end(), [&](const Vec3& q) { return same_norm(q, P[i]); }));
    if (c < a_count) {
      a_count = c;
      a = i;
    }
  }
  const Vec3 ah = P[a].normalized();
  std::size_t b = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (ah.cross(P[i]).norm() > ah.cross(P[b]).norm()) b = i;
  if (P[a].norm() <= tol || ah.cross(P[b]).norm() <= tol) {
    sym.note = "its corners are too close to the centre of mass to find its symmetry";
    return sym;
  }
  auto frame = [](const Vec3& x, const Vec3& y) {
    Mat3 F;
    F.col(0) = x.normalized();
    F.col(1) = (y - y.dot(F.col(0)) * F.col(0)).normalized();
    F.col(2) = F.col(0).cross(F.col(1));
    return F;
  };
  const Mat3 F = frame(P[a], P[b]);
  const double ab = ah.dot(P[b]);
  for (std::size_t i = 0; i < n; ++i) {
    if (!same_norm(P[i], P[a])) continue;
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i || !same_norm(P[j], P[b]) || std::abs(P[i].normalized().dot(P[j]) - ab) > tol) continue;
      const Mat3 S = frame(P[i], P[j]) * F.transpose();
      if (std::any_of(sym.rotations.begin(), sym.rotations.end(), [&](const Mat3& R) { return (R - S).norm() < 1e-6; }))
        continue;
      if (!maps_onto(S, P, true) || (!mesh_points.empty() && !maps_onto(S, mesh_points, false)) || !check.keeps_mass(S))
        continue;
      sym.rotations.push_back(S);
    }
  }
  sym.note = count_text(sym.rotations.size()) + " about the centre of mass carry the die (shape and materials) onto itself";
  return sym;
}

}  // namespace

DieSymmetry die_symmetry(const Body& body, const SceneDef& scene) {
  DieSymmetry sym = body.kind == "cylinder" ? cylinder_symmetry(body, scene) : polytope_symmetry(body, scene);
  const ThrowDef& t = scene.throw_;
  if (t.orientation.kind != OrientationKind::Uniform && sym.rotations.size() > 1) {
    sym.rotations.resize(1);
    sym.note += "; but the throw's orientation is not uniform (throw.orientation), so none of them makes two outcomes alike";
  } else if (t.spin.kind == SpinKind::BodyAxis && sym.rotations.size() > 1) {
    const Vec3 axis = t.spin.axis.normalized();
    const auto kept = std::partition(sym.rotations.begin() + 1, sym.rotations.end(),
                                     [&](const Mat3& S) { return (S * axis - axis).norm() < 1e-9; });
    sym.rotations.erase(kept, sym.rotations.end());
    sym.note += "; the throw spins it about a body axis (throw.spin.axis): " + count_text(sym.rotations.size()) + " keep that axis";
  }
  return sym;
}

std::vector<int> alike_outcome_classes(const Body& body, const std::vector<Mat3>& rotations) {
  std::vector<int> labels = body.face_labels;
  std::sort(labels.begin(), labels.end());
  labels.erase(std::unique(labels.begin(), labels.end()), labels.end());
  const std::size_t nf = body.face_labels.size(), no = labels.size();
  auto outcome_of = [&](std::size_t f) {
    return static_cast<std::size_t>(std::lower_bound(labels.begin(), labels.end(), body.face_labels[f]) - labels.begin());
  };
  std::vector<std::size_t> parent(no);
  std::iota(parent.begin(), parent.end(), std::size_t{0});
  auto root = [&](std::size_t k) {
    while (parent[k] != k) k = parent[k] = parent[parent[k]];
    return k;
  };
  std::vector<std::size_t> faces_of(no, 0);
  for (std::size_t f = 0; f < nf; ++f) ++faces_of[outcome_of(f)];
  for (const Mat3& S : rotations) {
    std::vector<std::size_t> image(nf, nf);  // face f -> the face S carries it onto
    if (body.kind == "cylinder") {
      const bool over = (S * Vec3::UnitZ()).z() < 0.0;
      image = {over ? 1u : 0u, over ? 0u : 1u, 2u};
    } else {
      for (std::size_t f = 0; f < nf; ++f)
        for (std::size_t g = 0; g < nf; ++g)
          if ((S * body.shape.normals[f] - body.shape.normals[g]).norm() < 1e-6) image[f] = g;
    }
    if (std::find(image.begin(), image.end(), nf) != image.end()) continue;
    // Outcome A is carried onto B when every face labelled A goes to a face labelled B (as many).
    for (std::size_t A = 0; A < no; ++A) {
      std::size_t B = no;
      bool one = true;
      for (std::size_t f = 0; f < nf; ++f) {
        if (outcome_of(f) != A) continue;
        const std::size_t o = outcome_of(image[f]);
        if (B == no) B = o;
        one = one && o == B;
      }
      if (one && B < no && faces_of[A] == faces_of[B]) parent[root(A)] = root(B);
    }
  }
  std::vector<int> cls(no, -1), first(no, -1);
  for (std::size_t k = 0; k < no; ++k) {
    const std::size_t r = root(k);
    if (first[r] < 0) first[r] = static_cast<int>(k);
    cls[k] = first[r];
  }
  return cls;
}

}  // namespace dicesim

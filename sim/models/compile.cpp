#include "sim/models/compile.hpp"
#include "sim/models/world_compile.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "sim/body/body.hpp"
#include "sim/body/rim.hpp"
#include "sim/body/symmetry.hpp"
#include "sim/dynamics/rim_rest.hpp"
#include "sim/models/fidelity_auto.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/dynamics/torque_free.hpp"

namespace dicesim {
namespace {

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}


// Corner adjacency, edge positions and the face across every edge, from the face loops. A loop
// edge a -> b must meet exactly one b -> a in another face (a closed, consistently oriented hull).
void build_topology(DieModel& m, const ConvexShape& shape, const std::string& origin, const std::string& kind) {
  const int nv = static_cast<int>(shape.vertices.size());
  m.face_begin.assign(1, 0);
  m.face_loop.clear();
  m.loop_face.clear();
  for (std::size_t f = 0; f < shape.faces.size(); ++f) {
    if (shape.faces[f].size() < 3)
      throw SceneError(origin, "die.shape", kind, "a face with fewer than 3 corners");
    for (const int v : shape.faces[f]) {
      if (v < 0 || v >= nv) throw SceneError(origin, "die.shape", kind, "a face refers to a missing corner");
      m.face_loop.push_back(v);
      m.loop_face.push_back(static_cast<int>(f));
    }
    m.face_begin.push_back(static_cast<int>(m.face_loop.size()));
  }
  std::map<std::pair<int, int>, int> edge_pos;  // directed edge -> loop position
  for (std::size_t f = 0; f < shape.faces.size(); ++f) {
    const int b0 = m.face_begin[f], k = m.face_begin[f + 1] - b0;
    for (int i = 0; i < k; ++i) {
      const int a = m.face_loop[static_cast<std::size_t>(b0 + i)];
      const int b = m.face_loop[static_cast<std::size_t>(b0 + (i + 1) % k)];
      if (!edge_pos.emplace(std::make_pair(a, b), b0 + i).second)
        throw SceneError(origin, "die.shape", kind, "two faces share an edge in the same direction (not a consistently oriented hull)");
    }
  }
  m.face_across.assign(m.face_loop.size(), -1);
  std::vector<std::vector<std::pair<int, int>>> adj(static_cast<std::size_t>(nv));  // (neighbour, edge position)
  for (const auto& [ab, pos] : edge_pos) {
    const auto it = edge_pos.find({ab.second, ab.first});
    if (it == edge_pos.end())
      throw SceneError(origin, "die.shape", kind, "an edge belongs to one face only (the hull is not closed)");
    m.face_across[static_cast<std::size_t>(pos)] = m.loop_face[static_cast<std::size_t>(it->second)];
    adj[static_cast<std::size_t>(ab.first)].push_back({ab.second, pos});
  }
  m.vertex_adj_begin.assign(1, 0);
  m.vertex_adj.clear();
  m.vertex_adj_edge.clear();
  for (auto& list : adj) {
    std::sort(list.begin(), list.end());
    for (const auto& [j, pos] : list) {
      m.vertex_adj.push_back(j);
      m.vertex_adj_edge.push_back(pos);
    }
    m.vertex_adj_begin.push_back(static_cast<int>(m.vertex_adj.size()));
  }
}

// Outcomes: distinct labels ascending; the face read when each face lies on the floor.
void build_outcomes(DieModel& m) {
  m.outcome_labels = m.face_labels;
  std::sort(m.outcome_labels.begin(), m.outcome_labels.end());
  m.outcome_labels.erase(std::unique(m.outcome_labels.begin(), m.outcome_labels.end()), m.outcome_labels.end());
  const int nf = m.face_count();
  m.face_outcome.resize(static_cast<std::size_t>(nf));
  m.face_result.resize(static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    const std::size_t fi = static_cast<std::size_t>(f);
    m.face_outcome[fi] = static_cast<int>(
        std::lower_bound(m.outcome_labels.begin(), m.outcome_labels.end(), m.face_labels[fi]) - m.outcome_labels.begin());
    if (m.read_down) {
      m.face_result[fi] = f;
      continue;
    }
    int up = f;
    double best = 2.0;
    for (int g = 0; g < nf; ++g) {
      const double z = m.face_normals[fi].dot(m.face_normals[static_cast<std::size_t>(g)]);
      if (z < best) {
        best = z;
        up = g;
      }
    }
    m.face_result[fi] = up;
  }
}

// The tie rule (a die read up). Resting on face f, the face read is the one whose outward normal
// is most nearly opposite f's. When several faces tie for that (cosines within 1e-9) and their
// labels differ, no face is up: the die lies with an edge or a corner on top, as on a corner cut
// off a 3-fold symmetric die. Such a face f that can hold the die is then read as its own label
// (it gets its own outcome), provided that label is f's alone and f is not also the face read
// from another resting face; otherwise the scene must settle it (a label of its own for f, one
// label for the tied faces, or read = "down"), and is refused naming the face. Never by index.
void resolve_read_ties(DieModel& m, const std::string& origin) {
  if (m.read_down || m.curved()) return;
  const int nf = m.face_count();
  auto normal_text = [&](int f) {
    const Vec3 n = m.geo_to_body.transpose() * m.face_normals[static_cast<std::size_t>(f)];
    return "(" + fmt(n.x()) + ", " + fmt(n.y()) + ", " + fmt(n.z()) + ")";
  };
  for (int f = 0; f < nf; ++f) {
    const std::size_t fi = static_cast<std::size_t>(f);
    if (m.face_hold[fi] < 0.0) continue;  // the die never rests on it
    const Vec3& n = m.face_normals[fi];
    const double best = n.dot(m.face_normals[static_cast<std::size_t>(m.face_result[fi])]);
    std::vector<int> tied;
    bool differ = false;
    for (int g = 0; g < nf; ++g)
      if (n.dot(m.face_normals[static_cast<std::size_t>(g)]) <= best + 1e-9) {
        tied.push_back(g);
        differ = differ || m.face_labels[static_cast<std::size_t>(g)] != m.face_labels[static_cast<std::size_t>(tied.front())];
      }
    if (!differ) continue;
    bool own = std::count(m.face_labels.begin(), m.face_labels.end(), m.face_labels[fi]) == 1;
    for (int h = 0; h < nf && own; ++h)
      own = !(h != f && m.face_hold[static_cast<std::size_t>(h)] >= 0.0 && m.face_result[static_cast<std::size_t>(h)] == f);
    if (!own) {
      std::string faces, labels;
      for (const int g : tied) {
        faces += (faces.empty() ? "" : ", ") + std::to_string(g);
        labels += (labels.empty() ? "" : ", ") + std::to_string(m.face_labels[static_cast<std::size_t>(g)]);
      }
      throw SceneError(origin, "die.labels", "face " + std::to_string(f) + " (label " + std::to_string(m.face_labels[fi]) +
                           ", outward normal " + normal_text(f) + ")",
                       "resting on it, faces " + faces + " (labels " + labels +
                           ") are equally near up, so no face is read; give it a label of its own (a [[die.labels]] "
                           "entry with its normal; it is then read as that label), give those faces one label, or "
                           "read = \"down\"");
    }
    m.own_read_faces.push_back(f);
  }
  for (const int f : m.own_read_faces) m.face_result[static_cast<std::size_t>(f)] = f;
}

// The outcomes the die's symmetry makes alike (sim/body/symmetry.hpp).
void find_alike_outcomes(DieModel& m, const Body& body, const SceneDef& scene) {
  const DieSymmetry sym = die_symmetry(body, scene);
  m.outcome_alike = alike_outcome_classes(body, sym.rotations);
  m.symmetry_rotations = static_cast<int>(sym.rotations.size());
  m.alike_note = sym.note;
}

// Settings, fidelity, and the check that the die starts above the floor (every shape).
void finish_model(DieModel& m, const SceneDef& scene, const std::string& origin) {
  m.gravity = scene.sim.gravity;
  m.step = scene.sim.step;
  m.sustained_step = m.curved() ? kContactStepCurved : kContactStepPolyhedron;
  m.contact_tol = scene.sim.contact_tol;
  m.contact_step = scene.sim.contact_step > 0.0 ? scene.sim.contact_step
                   : m.curved()                 ? kContactStepCurved
                                                : kContactStepPolyhedron;
  m.stop_speed = scene.sim.stop_speed;
  m.max_bounces = scene.sim.max_bounces;
  m.max_time = scene.sim.max_time;
  m.throw_ = scene.throw_;
  m.catch_end = scene.sim.end == EndKind::Catch;
  resolve_fidelity(scene, m);
  if (m.catch_end)
    m.fidelity_reason += "; sim.end = \"catch\": the die flies untouched to the catch (no floor), so no fidelity's contact model plays a part";

  // The die must start above the floor. With a random orientation any corner may point down, so
  // the mean COM height must clear the bounding sphere; with a fixed one, the lowest corner.
  const NormalScalar& h = scene.throw_.height;
  if (m.catch_end) {
    // Caught in the hand: the floor plays no part.
  } else if (scene.throw_.orientation.kind == OrientationKind::Fixed) {
    const Vec3 e = scene.throw_.orientation.euler_deg * (kPi / 180.0);
    const Mat3 R = euler_zxz(e.x(), e.y(), e.z()) * m.geo_to_body.transpose();
    double depth = 0.0;
    for (const Vec3& v : m.vertices) depth = std::max(depth, -(R * v).z() + m.rounding);
    if (m.curved()) depth = -rim_lowest(m, R);
    if (h.mean < depth - 1e-12 * m.bounding_radius)
      throw SceneError(origin, "throw.height.mean", fmt(h.mean),
                       "the die starts below the floor: in this orientation the COM must be at least " +
                           fmt(depth) + " m above it");
  } else if (h.mean < m.bounding_radius) {
    throw SceneError(origin, "throw.height.mean", fmt(h.mean),
                     "the die could start below the floor: with a random orientation the COM must be at "
                     "least the bounding radius " + fmt(m.bounding_radius) + " m above it");
  }
}

// What every shape starts from: its name, kind, mass and principal frame.
DieModel start_model(const Body& body, const SceneDef& scene) {
  DieModel m;
  m.name = scene.name;
  m.kind = body.kind;
  m.mass_geometric = body.mass;
  m.mass = body.mass.mass;
  m.principal_moments = body.mass.principal_moments;
  m.geo_to_body = body.mass.principal_axes.transpose();
  m.symmetric_top = is_symmetric_top(m.principal_moments);
  return m;
}

// A cylinder: principal frame, rim circles, three "faces" (heads, tails, side), rest geometry.
DieModel compile_cylinder(const Body& body, const SceneDef& scene, const std::string& origin) {
  if (body.face_labels.size() != 3 || body.vertex_restitution.size() != kRimFeatures ||
      body.vertex_friction.size() != kRimFeatures || body.vertex_rolling.size() != kRimFeatures ||
      body.vertex_pivoting.size() != kRimFeatures)
    throw SceneError(origin, "die.shape", body.kind, "the body is incomplete (labels or materials missing)");
  DieModel m = start_model(body, scene);
  const MassProperties& mp = m.mass_geometric;
  m.read_down = false;
  m.rounding = body.cylinder.rounding;

  Rims& rim = m.rims;
  rim.on = true;
  rim.centre = m.geo_to_body * (-mp.com);
  rim.axis = (m.geo_to_body * Vec3::UnitZ()).normalized();
  rim.perp = (m.geo_to_body * Vec3::UnitX()).normalized();
  rim.radius = body.cylinder.core_radius();
  rim.half = body.cylinder.core_half();
  for (int f = 0; f < kRimFeatures; ++f) {
    m.vertex_restitution.push_back(scene.floor.restitution ? *scene.floor.restitution : body.vertex_restitution[f]);
    m.vertex_friction.push_back(scene.floor.friction ? *scene.floor.friction : body.vertex_friction[f]);
    m.vertex_rolling.push_back(body.vertex_rolling[f]);
    m.vertex_pivoting.push_back(body.vertex_pivoting[f]);
  }
  // The farthest body point from the COM: on a rim circle (plus the rounding).
  const Vec3 o_perp = rim.centre - rim.centre.dot(rim.axis) * rim.axis;
  double reach = 0.0;
  for (double sgn : {1.0, -1.0}) {
    const double par = rim.centre.dot(rim.axis) + sgn * rim.half;
    reach = std::max(reach, std::hypot(par, o_perp.norm() + rim.radius));
  }
  m.bounding_radius = reach + m.rounding;

  m.face_normals = {rim.axis, -rim.axis, Vec3::Zero()};
  m.face_labels = body.face_labels;
  m.face_begin.assign(4, 0);  // no corner loops: the faces are discs and a curved side
  build_outcomes(m);
  m.face_result = {1, 0, 2};  // heads face down shows tails, tails face down heads, the side edge
  compute_rim_rest_geometry(m);
  compute_escapes(m);
  find_alike_outcomes(m, body, scene);
  m.max_friction = *std::max_element(m.vertex_friction.begin(), m.vertex_friction.end());
  finish_model(m, scene, origin);
  return m;
}

}  // namespace

DieModel compile(const SceneDef& scene, const std::string& origin) {
  if (!scene.dice.empty() || !scene.obstacles.empty()) return compile_world(scene, origin);
  return compile_body(build_body(scene, origin), scene, origin);
}

DieModel compile_body(const Body& body, const SceneDef& scene, const std::string& origin) {
  if (body.kind == "cylinder") return compile_cylinder(body, scene, origin);
  const ConvexShape& shape = body.shape;
  const std::size_t nv = shape.vertices.size(), nf = shape.faces.size();
  if (nv < 4 || nf < 4 || shape.normals.size() != nf || body.face_labels.size() != nf ||
      body.vertex_restitution.size() != nv || body.vertex_friction.size() != nv)
    throw SceneError(origin, "die.shape", body.kind, "the body is incomplete (corners, faces, normals, labels or materials missing)");

  DieModel m = start_model(body, scene);
  const MassProperties& mp = m.mass_geometric;
  m.convex = body.convex;
  m.read_down = body.read_down;
  m.rounding = shape.rounding;

  m.vertices.resize(nv);
  m.vertex_restitution.resize(nv);
  m.vertex_friction.resize(nv);
  double reach = 0.0;
  for (std::size_t c = 0; c < nv; ++c) {
    m.vertices[c] = m.geo_to_body * (shape.vertices[c] - mp.com);
    m.vertex_restitution[c] = scene.floor.restitution ? *scene.floor.restitution : body.vertex_restitution[c];
    m.vertex_friction[c] = scene.floor.friction ? *scene.floor.friction : body.vertex_friction[c];
    reach = std::max(reach, m.vertices[c].norm());
  }
  m.bounding_radius = reach + m.rounding;
  m.face_normals.resize(nf);
  m.face_labels = body.face_labels;
  for (std::size_t f = 0; f < nf; ++f) m.face_normals[f] = m.geo_to_body * shape.normals[f];
  build_topology(m, shape, origin, body.kind);
  build_outcomes(m);

  compute_rest_geometry(m);
  resolve_read_ties(m, origin);
  compute_escapes(m);  // the reads are final now
  find_alike_outcomes(m, body, scene);
  m.max_friction = *std::max_element(m.vertex_friction.begin(), m.vertex_friction.end());

  finish_model(m, scene, origin);
  return m;
}

}  // namespace dicesim

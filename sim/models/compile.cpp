#include "sim/models/compile.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "sim/body/body.hpp"
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

}  // namespace

DieModel compile(const SceneDef& scene, const std::string& origin) {
  const Body body = build_body(scene, origin);
  if (body.shape.vertices.size() != 8 || body.shape.faces.size() != 6)
    throw SceneError(origin, "die.shape", body.kind, "only a six-faced box can be simulated yet");

  DieModel m;
  m.name = scene.name;
  m.mass_geometric = body.mass;
  const MassProperties& mp = m.mass_geometric;

  m.mass = mp.mass;
  m.principal_moments = mp.principal_moments;
  m.geo_to_body = mp.principal_axes.transpose();
  m.symmetric_top = is_symmetric_top(m.principal_moments);

  for (int c = 0; c < 8; ++c) {
    m.vertices[c] = m.geo_to_body * (body.shape.vertices[c] - mp.com);
    m.vertex_restitution[c] = scene.floor.restitution ? *scene.floor.restitution : body.vertex_restitution[c];
    m.vertex_friction[c] = body.vertex_friction[c];
    m.bounding_radius = std::max(m.bounding_radius, m.vertices[c].norm());
  }
  for (int f = 0; f < 6; ++f) {
    m.face_normals[f] = m.geo_to_body * body.shape.normals[f];
    m.face_labels[f] = body.face_labels[f];
  }

  compute_rest_geometry(m);
  m.max_friction = *std::max_element(m.vertex_friction.begin(), m.vertex_friction.end());

  m.gravity = scene.sim.gravity;
  m.step = scene.sim.step;
  m.contact_step = scene.sim.contact_step;
  m.stop_speed = scene.sim.stop_speed;
  m.max_bounces = scene.sim.max_bounces;
  m.max_time = scene.sim.max_time;
  m.throw_ = scene.throw_;
  resolve_fidelity(scene, m);

  // The die must start above the floor. With a random orientation any corner may point down, so
  // the mean COM height must clear the bounding sphere; with a fixed one, the lowest corner.
  const NormalScalar& h = scene.throw_.height;
  if (scene.throw_.orientation.kind == OrientationKind::Fixed) {
    const Vec3 e = scene.throw_.orientation.euler_deg * (kPi / 180.0);
    const Mat3 R = euler_zxz(e.x(), e.y(), e.z()) * m.geo_to_body.transpose();
    double depth = 0.0;
    for (const Vec3& v : m.vertices) depth = std::max(depth, -(R * v).z());
    if (h.mean < depth - 1e-12 * m.bounding_radius)
      throw SceneError(origin, "throw.height.mean", fmt(h.mean),
                       "the die starts below the floor: in this orientation the COM must be at least " +
                           fmt(depth) + " m above it");
  } else if (h.mean < m.bounding_radius) {
    throw SceneError(origin, "throw.height.mean", fmt(h.mean),
                     "the die could start below the floor: with a random orientation the COM must be at "
                     "least the bounding radius " + fmt(m.bounding_radius) + " m above it");
  }
  return m;
}

}  // namespace dicesim

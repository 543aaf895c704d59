#include "sim/models/compile.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "sim/models/fidelity_auto.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/dynamics/torque_free.hpp"

namespace dicesim {
namespace {

std::string region_key(std::size_t k) { return "die.regions[" + std::to_string(k) + "]"; }

std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Regions must each cover some of the box and must not overlap: the density field is then
// unambiguous, and mass properties are the exact sum over regions.
void check_regions(const DieDef& die, const std::string& origin) {
  const double box_volume = die.size.prod();
  const double tiny = 1e-9 * box_volume;
  for (std::size_t k = 0; k < die.regions.size(); ++k) {
    if (clipped_box_moments(die.size, die.regions[k].half_spaces).volume <= tiny)
      throw SceneError(origin, region_key(k) + ".cuts", "", "the cuts leave no part of the die for this region");
    for (std::size_t j = 0; j < k; ++j) {
      std::vector<HalfSpace> both = die.regions[j].half_spaces;
      both.insert(both.end(), die.regions[k].half_spaces.begin(), die.regions[k].half_spaces.end());
      if (clipped_box_moments(die.size, both).volume > tiny)
        throw SceneError(origin, region_key(k) + ".cuts", "",
                         "overlaps " + region_key(j) + "; regions must not overlap");
    }
  }
}

// A corner's material: the volume-weighted mix of the materials in a small cube at that corner
// (a cut through a corner, as the seed's Die 3 has, gives a mix instead of an arbitrary pick).
void corner_materials(const DieDef& die, const std::map<std::string, MaterialDef>& materials, int corner,
                      double& restitution, double& friction) {
  const Vec3 half = 0.5 * die.size;
  const double eps = 1e-6 * die.size.minCoeff();
  Vec3 lo, hi;
  for (int a = 0; a < 3; ++a) {
    const bool plus = (corner >> a) & 1;
    lo[a] = plus ? half[a] - eps : -half[a];
    hi[a] = plus ? half[a] : -half[a] + eps;
  }
  const double v = (hi - lo).prod();
  double base_fraction = 1.0;
  restitution = friction = 0.0;
  for (const RegionDef& r : die.regions) {
    const double f = clipped_aabb_moments(lo, hi, r.half_spaces).volume / v;
    if (f <= 0.0) continue;
    base_fraction -= f;
    restitution += f * materials.at(r.material).restitution;
    friction += f * materials.at(r.material).friction;
  }
  base_fraction = std::max(0.0, base_fraction);
  restitution += base_fraction * materials.at(die.base_material).restitution;
  friction += base_fraction * materials.at(die.base_material).friction;
}

}  // namespace

DieModel compile(const SceneDef& scene, const std::string& origin) {
  const DieDef& die = scene.die;
  check_regions(die, origin);

  DieModel m;
  m.name = scene.name;
  m.mass_geometric = compute_mass_properties(die, scene.materials);
  const MassProperties& mp = m.mass_geometric;
  if (!(mp.mass > 0.0) || !mp.inertia.allFinite())
    throw SceneError(origin, "die", "", "the die has no mass; check die.size and the densities");

  m.mass = mp.mass;
  m.principal_moments = mp.principal_moments;
  m.geo_to_body = mp.principal_axes.transpose();
  m.symmetric_top = is_symmetric_top(m.principal_moments);

  const Vec3 half = 0.5 * die.size;
  for (int c = 0; c < 8; ++c) {
    Vec3 corner;
    for (int a = 0; a < 3; ++a) corner[a] = ((c >> a) & 1) ? half[a] : -half[a];
    m.vertices[c] = m.geo_to_body * (corner - mp.com);
    corner_materials(die, scene.materials, c, m.vertex_restitution[c], m.vertex_friction[c]);
    if (scene.floor.restitution) m.vertex_restitution[c] = *scene.floor.restitution;
    m.bounding_radius = std::max(m.bounding_radius, m.vertices[c].norm());
  }
  for (int f = 0; f < 6; ++f) {
    Vec3 n = Vec3::Zero();
    n[f / 2] = (f % 2 == 0) ? 1.0 : -1.0;
    m.face_normals[f] = m.geo_to_body * n;
  }
  m.face_labels = die.face_labels;

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

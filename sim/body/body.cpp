#include "sim/body/body.hpp"

#include <algorithm>
#include <string>

#include "sim/scene/scene_error.hpp"

namespace dicesim {
namespace {

std::string region_key(std::size_t k) { return "die.regions[" + std::to_string(k) + "]"; }

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

Body build_body(const SceneDef& scene, const std::string& origin) {
  const DieDef& die = scene.die;
  check_regions(die, origin);

  Body b;
  b.kind = "box";
  b.shape = box_shape(die.size);
  b.face_labels.assign(die.face_labels.begin(), die.face_labels.end());
  b.mass = compute_mass_properties(die, scene.materials);
  if (!(b.mass.mass > 0.0) || !b.mass.inertia.allFinite())
    throw SceneError(origin, "die", "", "the die has no mass; check die.size and the densities");
  const std::size_t n = b.shape.vertices.size();
  b.vertex_restitution.resize(n);
  b.vertex_friction.resize(n);
  for (std::size_t c = 0; c < n; ++c)
    corner_materials(die, scene.materials, static_cast<int>(c), b.vertex_restitution[c], b.vertex_friction[c]);
  return b;
}

}  // namespace dicesim

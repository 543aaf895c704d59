#include "sim/body/body.hpp"
#include "sim/body/material_parts.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>

#include "sim/body/hull.hpp"
#include "sim/body/labels.hpp"
#include "sim/body/mesh.hpp"
#include "sim/body/presets.hpp"
#include "sim/body/rounding.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim {
namespace {

std::string region_key(std::size_t k) { return "die.regions[" + std::to_string(k) + "]"; }

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Volume moments of the die's solid intersected with a list of half-spaces.
using SolidMoments = std::function<VolumeMoments(const std::vector<HalfSpace>&)>;

// Regions must each cover some of the die and must not overlap: the density field is then
// unambiguous, and mass properties are the exact sum over regions.
// `parts` (if given): the die's volume and each region's, for material_parts (`info`).
void check_regions(const DieDef& die, const SolidMoments& solid, double volume, const std::string& origin,
                   std::vector<double>* parts) {
  const double tiny = 1e-9 * volume;
  if (parts) parts->assign(1, volume);
  for (std::size_t k = 0; k < die.regions.size(); ++k) {
    const double v = solid(die.regions[k].half_spaces).volume;
    if (parts) parts->push_back(v);
    if (v <= tiny)
      throw SceneError(origin, region_key(k) + ".cuts", "", "the cuts leave no part of the die for this region");
    for (std::size_t j = 0; j < k; ++j) {
      std::vector<HalfSpace> both = die.regions[j].half_spaces;
      both.insert(both.end(), die.regions[k].half_spaces.begin(), die.regions[k].half_spaces.end());
      if (solid(both).volume > tiny)
        throw SceneError(origin, region_key(k) + ".cuts", "",
                         "overlaps " + region_key(j) + "; regions must not overlap");
    }
  }
}

// Base density everywhere, each region corrected to its own density (exact: regions are disjoint).
MassProperties layered_mass(const DieDef& die, const std::map<std::string, MaterialDef>& materials,
                            const SolidMoments& solid) {
  const double base_density = materials.at(die.base_material).density;
  VolumeMoments weighted;
  accumulate(weighted, solid({}), base_density);
  for (const RegionDef& region : die.regions)
    accumulate(weighted, solid(region.half_spaces), materials.at(region.material).density - base_density);
  return mass_properties_from_moments(weighted);
}

// A box corner's material: the volume-weighted mix of the materials in a small cube at that corner
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

// Any other shape's vertex: the same mix over a small cube about the vertex, clipped to the die
// near it (the planes of the faces at that vertex, moved out by the rounding). The cube's half
// side is the rounding radius, or 1e-6 of the die's size for a sharp die.
void vertex_materials(const DieDef& die, const std::map<std::string, MaterialDef>& materials, const ConvexShape& s,
                      std::vector<double>& restitution, std::vector<double>& friction) {
  const std::size_t n = s.vertices.size();
  const MaterialDef& base = materials.at(die.base_material);
  restitution.assign(n, base.restitution);
  friction.assign(n, base.friction);
  if (die.regions.empty()) return;
  Vec3 lo = s.vertices[0], hi = lo;
  for (const Vec3& v : s.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double h = s.rounding > 0.0 ? s.rounding : 1e-6 * (hi - lo).norm();
  std::vector<std::vector<HalfSpace>> planes(n);
  for (std::size_t f = 0; f < s.faces.size(); ++f)
    for (int v : s.faces[f])
      planes[v].push_back({s.normals[f], s.normals[f].dot(s.vertices[v]) + s.rounding});
  for (std::size_t v = 0; v < n; ++v) {
    const Vec3 a = s.vertices[v] - Vec3::Constant(h), b = s.vertices[v] + Vec3::Constant(h);
    const double whole = clipped_aabb_moments(a, b, planes[v]).volume;
    if (!(whole > 0.0)) continue;
    double base_fraction = 1.0, e = 0.0, mu = 0.0;
    for (const RegionDef& r : die.regions) {
      std::vector<HalfSpace> cuts = planes[v];
      cuts.insert(cuts.end(), r.half_spaces.begin(), r.half_spaces.end());
      const double f = clipped_aabb_moments(a, b, cuts).volume / whole;
      if (f <= 0.0) continue;
      base_fraction -= f;
      e += f * materials.at(r.material).restitution;
      mu += f * materials.at(r.material).friction;
    }
    base_fraction = std::max(0.0, base_fraction);
    restitution[v] = e + base_fraction * base.restitution;
    friction[v] = mu + base_fraction * base.friction;
  }
}

// Today's box, bit for bit (the paper regression counts depend on it).
Body build_box(const SceneDef& scene, const std::string& origin, std::vector<double>* parts) {
  const DieDef& die = scene.die;
  const SolidMoments solid = [&](const std::vector<HalfSpace>& cuts) { return clipped_box_moments(die.size, cuts); };
  check_regions(die, solid, die.size.prod(), origin, parts);
  Body b;
  b.kind = "box";
  b.shape = box_shape(die.size);
  b.face_labels = face_labels(b.shape, die, origin);
  b.read_down = die.read_down.value_or(false);
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

ConvexShape hull_or_error(const std::vector<Vec3>& points, const std::string& origin, const std::string& key) {
  try {
    return convex_hull(points);
  } catch (const HullError& e) {
    throw SceneError(origin, key, "", std::string("no solid convex hull: ") + e.what());
  }
}

// A cylinder: exact mass properties (regions included) and per-rim materials.
Body build_cylinder(const SceneDef& scene, const std::string& origin, std::vector<double>* parts) {
  const DieDef& die = scene.die;
  Body b;
  b.kind = "cylinder";
  b.cylinder = CylinderShape{die.radius, die.height, die.rounding};
  if (!(die.rounding < std::min(die.radius, 0.5 * die.height)))
    throw SceneError(origin, "die.rounding", num(die.rounding), "must be below min(radius, height/2)");
  const CylinderShape c = b.cylinder;
  const SolidMoments solid = [c](const std::vector<HalfSpace>& cuts) { return cylinder_moments(c, cuts); };
  check_regions(die, solid, solid({}).volume, origin, parts);
  b.face_labels = {die.cylinder_labels[0], die.cylinder_labels[1], die.cylinder_labels[2]};
  b.mass = layered_mass(die, scene.materials, solid);
  if (!(b.mass.mass > 0.0) || !b.mass.inertia.allFinite())
    throw SceneError(origin, "die", "", "the die has no mass; check its size and the densities");
  // Each rim's materials: the volume mix in the outer skin of its face (a slab of thickness
  // max(rounding, 1e-6 height)), the same for the rim's three features.
  const double skin = std::max(die.rounding, 1e-6 * die.height);
  for (int k = 0; k < 2; ++k) {
    const double sgn = k == 0 ? 1.0 : -1.0;
    const std::vector<HalfSpace> slab = {{Vec3(0, 0, -sgn), -(0.5 * die.height - skin)}};
    const double whole = solid(slab).volume;
    const MaterialDef& base = scene.materials.at(die.base_material);
    double fb = 1.0, e = 0.0, mu = 0.0, rr = 0.0, rp = 0.0;
    for (const RegionDef& r : die.regions) {
      std::vector<HalfSpace> cuts = slab;
      cuts.insert(cuts.end(), r.half_spaces.begin(), r.half_spaces.end());
      const double f = whole > 0.0 ? solid(cuts).volume / whole : 0.0;
      if (f <= 0.0) continue;
      const MaterialDef& mat = scene.materials.at(r.material);
      fb -= f;
      e += f * mat.restitution;
      mu += f * mat.friction;
      rr += f * mat.rolling_resistance;
      rp += f * mat.pivoting_resistance;
    }
    fb = std::max(0.0, fb);
    for (int j = 0; j < 3; ++j) {
      b.vertex_restitution.push_back(e + fb * base.restitution);
      b.vertex_friction.push_back(mu + fb * base.friction);
      b.vertex_rolling.push_back(rr + fb * base.rolling_resistance);
      b.vertex_pivoting.push_back(rp + fb * base.pivoting_resistance);
    }
  }
  return b;
}

// The body, and (if `parts` is given) the volumes check_regions measures.
Body build_body_measured(const SceneDef& scene, const std::string& origin, std::vector<double>* parts) {
  const DieDef& die = scene.die;
  if (die.shape == ShapeKind::Cylinder) return build_cylinder(scene, origin, parts);
  if (die.shape == ShapeKind::Box && die.rounding == 0.0) return build_box(scene, origin, parts);

  Body b;
  b.kind = kShapeNames[static_cast<int>(die.shape)];
  ConvexShape outer;
  Triangles mesh_surface;  // a mesh's own surface (mass comes from it, not from its hull)
  switch (die.shape) {
    case ShapeKind::Box:
      outer = box_shape(die.size);
      break;
    case ShapeKind::Prism:
      outer = prism_shape(die.sides, die.radius, die.length);
      break;
    case ShapeKind::Hull: {
      std::vector<Vec3> points = die.vertices;
      for (Vec3& p : points) p *= die.scale;
      outer = hull_or_error(points, origin, "die.vertices");
      break;
    }
    case ShapeKind::Mesh: {
      const ObjMesh mesh = parse_obj(die.mesh_text, die.mesh_path);
      check_closed(mesh, die.mesh_path);
      outer = hull_or_error(used_vertices(mesh, die.scale), die.mesh_path, "die.mesh");
      mesh_surface = mesh_triangles(mesh, die.scale);
      break;
    }
    default:
      outer = preset_shape(die.shape, die.size.x());
  }

  SolidMoments solid;
  std::shared_ptr<RoundedSolid> rounded;
  if (die.rounding > 0.0) {
    try {
      b.shape = shrink_shape(outer, die.rounding);
    } catch (const HullError&) {
      throw SceneError(origin, "die.rounding", num(die.rounding),
                       "must be below the die's inradius (the largest ball inside it), " + num(inradius(outer)) + " m");
    }
    rounded = std::make_shared<RoundedSolid>(b.shape, die.rounding);
    solid = [rounded](const std::vector<HalfSpace>& cuts) { return rounded->moments(cuts); };
  } else {
    b.shape = outer;
    if (mesh_surface.empty()) mesh_surface = shape_triangles(outer);
    solid = [surface = std::move(mesh_surface)](const std::vector<HalfSpace>& cuts) {
      return clipped_surface_moments(surface, cuts);
    };
  }
  const double volume = solid({}).volume;
  if (die.shape == ShapeKind::Mesh) {
    const double hull_volume = surface_moments(shape_triangles(b.shape)).volume;
    b.convex = std::abs(hull_volume - volume) <= 1e-9 * hull_volume;
  }

  b.face_labels = face_labels(b.shape, die, origin);
  b.read_down = die.read_down.value_or(die.shape == ShapeKind::D4);
  check_regions(die, solid, volume, origin, parts);
  b.mass = layered_mass(die, scene.materials, solid);
  if (!(b.mass.mass > 0.0) || !b.mass.inertia.allFinite())
    throw SceneError(origin, "die", "", "the die has no mass; check its size and the densities");
  vertex_materials(die, scene.materials, b.shape, b.vertex_restitution, b.vertex_friction);
  return b;
}

}  // namespace

Body build_body(const SceneDef& scene, const std::string& origin) { return build_body_measured(scene, origin, nullptr); }

std::vector<MaterialPart> material_parts(const SceneDef& scene, const std::string& origin) {
  std::vector<double> volumes;  // the die's, then each region's
  build_body_measured(scene, origin, &volumes);
  const DieDef& die = scene.die;
  std::vector<MaterialPart> parts;
  double in_regions = 0.0;
  for (std::size_t k = 1; k < volumes.size(); ++k) in_regions += volumes[k];
  const double base_density = scene.materials.at(die.base_material).density;
  const double base_volume = std::max(0.0, volumes.at(0) - in_regions);  // regions are disjoint (checked)
  parts.push_back({"base", die.base_material, base_density, base_volume, base_density * base_volume});
  for (std::size_t k = 0; k < die.regions.size() && k + 1 < volumes.size(); ++k) {
    const double rho = scene.materials.at(die.regions[k].material).density;
    parts.push_back({"region " + std::to_string(k), die.regions[k].material, rho, volumes[k + 1], rho * volumes[k + 1]});
  }
  return parts;
}

}  // namespace dicesim

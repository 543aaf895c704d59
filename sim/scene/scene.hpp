// What a user writes: the scene definition, its defaults (one place), and loading from TOML.
// A SceneDef is plain data; DieModel (die_model.hpp) is what a toss reads once it is compiled.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sim/scene/fidelity.hpp"
#include "sim/math.hpp"

namespace dicesim {

struct MaterialDef {
  double density = 1000.0;    // kg/m^3, > 0
  double restitution = 0.5;   // [0, 1] against the floor
  double friction = 0.3;      // Coulomb coefficient against the floor, [0, 10]
};

// Half-space {x : normal . x <= offset} in the die's geometric frame (origin at the box centre, m).
struct HalfSpace {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
};

// A convex region of the box: the box intersected with every half-space listed.
// Regions must not overlap; what no region covers is made of DieDef::base_material.
struct RegionDef {
  std::string material;
  std::vector<HalfSpace> half_spaces;
};

// Outward face normals of a box, in this order everywhere: +x, -x, +y, -y, +z, -z.
enum class FaceDir { PosX = 0, NegX = 1, PosY = 2, NegY = 3, PosZ = 4, NegZ = 5 };
inline constexpr std::array<const char*, 6> kFaceDirNames = {"+x", "-x", "+y", "-y", "+z", "-z"};

struct DieDef {
  Vec3 size = Vec3(0.03, 0.03, 0.03);  // edge lengths along x, y, z (m)
  std::string base_material;           // required
  std::vector<RegionDef> regions;      // optional cuts of other materials
  // Label of the face whose outward normal is +x, -x, +y, -y, +z, -z (a standard die by default:
  // 1 up on +z, opposite faces sum to 7).
  std::array<int, 6> face_labels = {2, 5, 3, 4, 1, 6};
};

enum class OrientationKind { Uniform, EulerUniform, Fixed };
struct OrientationDef {
  OrientationKind kind = OrientationKind::Uniform;
  Vec3 euler_deg = Vec3::Zero();  // psi, theta, phi (z-x-z), degrees; used when kind == Fixed
};

// A scalar that is normal(mean, sd); sd = 0 makes it fixed.
struct NormalScalar {
  double mean = 0.0;
  double sd = 0.0;
};

// A vector whose components are independent normals (sd = 0: fixed component).
struct NormalVector {
  Vec3 mean = Vec3::Zero();
  Vec3 sd = Vec3::Zero();
};

enum class SpinKind {
  Normal,       // each world component ~ normal(mean_i, sd_i)
  RandomAxis,   // magnitude ~ normal(mean, sd) along an axis uniform on the sphere
  OctantAxis,   // magnitude ~ normal(mean, sd) along the seed's axis: components uniform [0,1], normalised
};
struct SpinDef {
  SpinKind kind = SpinKind::Normal;
  NormalVector components;   // kind == Normal (rad/s, world frame)
  NormalScalar magnitude;    // kind == RandomAxis / OctantAxis (rad/s)
};

struct ThrowDef {
  OrientationDef orientation;
  NormalScalar height{1.0, 0.2};                                      // COM height above floor (m)
  NormalVector velocity{Vec3::Zero(), Vec3::Constant(0.5)};           // COM velocity (m/s)
  SpinDef spin{SpinKind::Normal, {Vec3::Zero(), Vec3::Constant(18.0)}, {}};
};

struct FloorDef {
  // When set, every contact uses this restitution instead of the die material's
  // (the seed's sec. 5.8 sweep: "same for all corners").
  std::optional<double> restitution;
};

struct SimDef {
  Fidelity fidelity = Fidelity::Paper;
  double gravity = 9.81;        // m/s^2
  double stop_speed = 0.1;      // m/s: `paper` stops when the COM's rebound speed is below this
  int max_bounces = 1000;       // a toss with more impacts is `unresolved`
  double max_time = 60.0;       // s of simulated time; longer is `unresolved`
  // Accuracy settings of the fidelity ladder (docs/fidelity.md measures what they cost and change).
  double step = 2e-4;           // s: `stepped`'s fixed time step (the reference)
  double contact_step = 1e-3;   // s: `impulse`'s time step while the die rolls/slides in sustained contact
};

struct SceneDef {
  std::string name;
  std::map<std::string, MaterialDef> materials;
  DieDef die;
  ThrowDef throw_;
  FloorDef floor;
  SimDef sim;
};

// The one place that lists every option's default (as the member initialisers above).
SceneDef default_scene_def();

// Reads a scene file, applies `overrides` ("key.path=value", TOML syntax for the value),
// validates everything, and returns it. Throws SceneError (scene_error.hpp) naming the
// file, key, value and allowed range.
SceneDef load_scene(const std::string& path, const std::vector<std::string>& overrides = {});

// The same from text already in memory (`origin` names it in errors).
SceneDef parse_scene(const std::string& toml_text, const std::string& origin,
                     const std::vector<std::string>& overrides = {});

}  // namespace dicesim

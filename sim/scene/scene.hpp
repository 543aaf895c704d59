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
  // Rolling resistance (m): the floor's normal force N acts this far ahead of a rolling contact,
  // a torque N * rolling_resistance against the roll. Used by curved dice (a cylinder) in
  // `impulse` and `stepped`, so that a cylinder rolling on its side comes to rest. [0, 0.1].
  // Default 3e-4 m: a coin rolling on hardwood slows by ~0.2 m/s^2 (an order of magnitude).
  double rolling_resistance = 3e-4;
  // Pivoting (torsional) resistance (m): a torque N * pivoting_resistance against the die's spin
  // about the floor's normal while it stands on one point, the friction of the contact patch that
  // a point contact leaves out (a coin spinning upright on its rim never slowed). Curved dice in
  // `impulse` and `stepped`. [0, 0.1]. Default 3e-6 m: (3 pi / 16) mu a for a Hertz patch of
  // radius a ~ 20 um (a coin's rim rounded 0.2 mm on hardwood under its weight), mu = 0.3.
  double pivoting_resistance = 3e-6;
};

// Half-space {x : normal . x <= offset} in the die's geometric frame (m): origin at the centre for a
// box, preset or prism; the coordinates as given for a hull or mesh.
struct HalfSpace {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0.0;
};

// A convex region of the die: the die intersected with every half-space listed.
// Regions must not overlap; what no region covers is made of DieDef::base_material.
struct RegionDef {
  std::string material;
  std::vector<HalfSpace> half_spaces;
};

// Outward face normals of a box, in this order everywhere: +x, -x, +y, -y, +z, -z.
enum class FaceDir { PosX = 0, NegX = 1, PosY = 2, NegY = 3, PosZ = 4, NegZ = 5 };
inline constexpr std::array<const char*, 6> kFaceDirNames = {"+x", "-x", "+y", "-y", "+z", "-z"};

// The kinds of die (die.shape). Box is today's six-faced box; the presets are the regular solids
// (d10: the pentagonal trapezohedron); prism: a regular n-gon prism; hull: the convex hull of
// listed points; mesh: a closed Wavefront OBJ (contact on its hull, mass from the mesh itself);
// cylinder: a right circular cylinder (a coin), its curved side exact (not a polytope).
enum class ShapeKind { Box, D4, D6, D8, D10, D12, D20, Prism, Hull, Mesh, Cylinder };
inline constexpr std::array<const char*, 11> kShapeNames = {"box", "d4",   "d6",   "d8",   "d10",     "d12",
                                                            "d20", "prism", "hull", "mesh", "cylinder"};

// A cylinder's outcomes, in this order everywhere: heads (+z face up), tails (-z face up), edge
// (resting on the curved side).
inline constexpr std::array<const char*, 3> kCylinderOutcomeNames = {"heads", "tails", "edge"};

// [[die.labels]]: the face whose outward normal is nearest `normal` gets `label`.
struct LabelDef {
  Vec3 normal = Vec3::UnitZ();
  int label = 1;
};

struct DieDef {
  ShapeKind shape = ShapeKind::Box;
  // box: edge lengths along x, y, z (m). d4..d20: size.x() is the distance between opposite faces
  // (d4: from a face to the opposite vertex); the scene gives it as one number.
  Vec3 size = Vec3(0.03, 0.03, 0.03);
  int sides = 3;                       // prism: number of sides of the regular n-gon, >= 3
  double radius = 0.01;                // prism: circumradius of the n-gon; cylinder: radius (m)
  double height = 0.002;               // cylinder: thickness along z (m)
  double length = 0.05;                // prism: length along z (m)
  std::vector<Vec3> vertices;          // hull: the points whose convex hull is the die (m)
  std::string mesh;                    // mesh: the OBJ path as written in the scene
  std::string mesh_path;               // mesh: that path resolved against the scene file's folder
  std::string mesh_text;               // mesh: the OBJ file's text, read when the scene is loaded
  double scale = 1.0;                  // hull, mesh: coordinates are multiplied by this (e.g. 0.001 for mm)
  double rounding = 0.0;               // radius of the rounded edges and corners (m), below the inradius
  std::optional<bool> read_down;       // read = "down" / "up"; unset: the shape's default (d4 down)
  std::vector<LabelDef> labels;        // [[die.labels]], applied after the shape's own labels
  std::string base_material;           // required
  std::vector<RegionDef> regions;      // optional cuts of other materials
  // Box (and d6): label of the face whose outward normal is +x, -x, +y, -y, +z, -z (a standard die
  // by default: 1 up on +z, opposite faces sum to 7).
  std::array<int, 6> face_labels = {2, 5, 3, 4, 1, 6};
  // Cylinder: labels of heads, tails, edge ([die.faces] heads/tails/edge), integers in [0, 999].
  std::array<int, 3> cylinder_labels = {1, 2, 0};
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
  BodyAxis,     // a flipping thumb: magnitude ~ normal(mean, sd) at angle ~ normal(tilt, tilt_sd) from a
                // body-frame axis, azimuth uniform (geometric frame of the die)
};
struct SpinDef {
  SpinKind kind = SpinKind::Normal;
  NormalVector components;   // kind == Normal (rad/s, world frame)
  NormalScalar magnitude;    // kind == RandomAxis / OctantAxis / BodyAxis (rad/s)
  Vec3 axis = Vec3::UnitX(); // kind == BodyAxis: in the die's geometric frame, not zero
  NormalScalar tilt_deg;     // kind == BodyAxis: angle of the angular velocity from `axis` (deg)
};

// throw.hand, for a scene with [[dice]]: "each" (every die draws its own throw: release height,
// velocity, orientation, spin) or "shared" (one hand: the release position and the velocity are
// drawn once and shared by every die, each die then at its [[dice]] offset from it; each die draws
// its own orientation and spin).
enum class HandKind { Each, Shared };

struct ThrowDef {
  OrientationDef orientation;
  NormalScalar height{1.0, 0.2};                                      // COM height above floor (m)
  NormalVector velocity{Vec3::Zero(), Vec3::Constant(0.5)};           // COM velocity (m/s)
  SpinDef spin{SpinKind::Normal, {Vec3::Zero(), Vec3::Constant(18.0)}, {}, Vec3::UnitX(), {}};
  // sim.end = "catch": the time after release at which the die is caught (s), normal(mean, sd).
  std::optional<NormalScalar> catch_time;
  HandKind hand = HandKind::Each;  // throw.hand ("each" / "shared"); only with [[dice]]
};

// How a toss ends: on the floor (the fidelity's dynamics), or caught in the hand in mid-flight
// (exact flight only; the result is the face most nearly up at the catch, never `edge`).
enum class EndKind { Floor, Catch };

struct FloorDef {
  // When set, every contact uses this restitution instead of the die material's
  // (the seed's sec. 5.8 sweep: "same for all corners").
  std::optional<double> restitution;
  // Likewise friction, in [0, 10]: the table's own coefficient, so that a fit can vary it alone.
  std::optional<double> friction;
};

// `impulse`'s default contact step. A polyhedron's sustained contact is mostly events (each new
// corner's touch located exactly; its held corners kept on the floor, and the step shortened
// where the die's spin would sink them: contact_stepper.hpp), and at 3 ms its faces are where a
// 10x finer step puts them on Dice 1-3, the fair die and the d20 (docs/fidelity.md, "Convergence
// as equivalence tests").
// A cylinder's rim steps are drift-kick-drift, second order (rim_step.cpp): the quarter dropped
// from 1 m reads the same edge rate at 1, 0.5, 0.2 and 0.1 ms (docs/fidelity.md, "Coins"); 0.2 ms
// is kept as the default until its equivalence with 1 ms is shown at 10^5 tosses.
inline constexpr double kContactStepPolyhedron = 3e-3;
inline constexpr double kContactStepCurved = 2e-4;
// sim.contact_tol > 0: a polyhedron's sustained contact in `impulse` is leapfrog with an
// error-controlled step (contact_stepper.hpp, AdaptiveSteps): the tolerance bounds each step's
// estimated position error of any body point, relative to the die's bounding radius; the contact
// step above is then the ceiling, kContactStepFloor the floor (located steps, which end at a new
// contact's instant, may be shorter). 0 (the default): fixed first-order steps of the contact step.
// Experimental, not the default: on five dice at 3*10^5 tosses it leaves the faces where fixed
// 3 ms steps put them, at 2.5-2.7x the cost, and its energy bound is m (g h)^2 / 8 a step rather
// than rounding (docs/fidelity.md, "Leapfrog steps"). Curved dice ignore it (their steps are
// always drift-kick-drift, at the fixed contact step).
inline constexpr double kContactTolDefault = 0.0;
inline constexpr double kContactStepFloor = 1e-4;

struct SimDef {
  // A scene file without sim.fidelity reads as Auto (build() in scene.cpp); Paper here only for
  // scenes built in code (tests, which state their model).
  Fidelity fidelity = Fidelity::Paper;
  double gravity = 9.81;        // m/s^2
  double stop_speed = 0.1;      // m/s: `paper` stops when the COM's rebound speed is below this
  int max_bounces = 1000;       // a toss with more impacts is `unresolved`
  double max_time = 60.0;       // s of simulated time; longer is `unresolved`
  // Accuracy settings of the fidelity ladder (docs/fidelity.md measures what they cost and change).
  double step = 2e-4;           // s: `stepped`'s fixed time step (the reference)
  double contact_step = 0.0;    // s: the ceiling of `impulse`'s sustained-contact step; 0: the shape's default (above)
  double contact_tol = kContactTolDefault;  // `impulse`'s sustained-contact error per step / bounding radius; 0: fixed steps (polyhedra only)
  EndKind end = EndKind::Floor; // "floor" or "catch" (needs [throw.catch_time])
};

// One [[dice]] entry: a die of a toss of several dice (issue 41).
struct DiceEntryDef {
  // `scene = "path"` as written: a scene file (relative to the file that states the key, with its
  // own `extends`) whose [die] this die is; "" (or the key left out): this scene's own [die].
  std::string scene;
  // The die: this scene's [die], or the [die] of that scene file.
  DieDef die;
  // The materials that die refers to: its scene's [materials] (all of them).
  std::map<std::string, MaterialDef> materials;
  // `offset = [x, y, z]` (m), added to the release position of the throw (finite, |offset| <= 1 m).
  Vec3 offset = Vec3::Zero();
};

// [outcomes] kind, for a scene with [[dice]]: "tuple" (the dice's labels in entry order, e.g. (3, 5))
// or "sum" (the sum of the dice's labels, e.g. 8).
enum class OutcomeKind { Tuple, Sum };
inline constexpr std::array<const char*, 2> kOutcomeKindNames = {"tuple", "sum"};
struct OutcomesDef {
  OutcomeKind kind = OutcomeKind::Tuple;
};

// [[obstacles]] kind. Every obstacle is static and made of convex pieces (sim/body/obstacles.hpp
// expands the compositions); the floor z = 0 stays the resting surface and is not an obstacle.
enum class ObstacleKind { Plane, Polyhedron, Box, Tray, Backboard, Tower, Cup };
inline constexpr std::array<const char*, 7> kObstacleKindNames = {"plane", "polyhedron", "box", "tray",
                                                                  "backboard", "tower", "cup"};

// Defaults of a craps backboard's pyramids (kind = "backboard"). No public regulation or maker's
// sheet found gives the pyramids' size (casinos choose it: F. Scoblete, "Get Yourself a Table",
// goldentouchcraps.com/scoblete_articles_0025.shtml), so base, height and pitch are NOT cited:
// plausible values (a base about a casino die's 19 mm edge, half as high, touching). The wall's
// height is cited: "Below the rail rubber on each inside end of the table is a 6-to-8-inch wide
// piece of Pyramid Rubber" (newcasinonodepositbonus.co.uk/craps-table-and-equipment.php); 7 in.
inline constexpr double kPyramidBase = 0.02;     // m, NOT cited
inline constexpr double kPyramidHeight = 0.01;   // m, NOT cited
inline constexpr double kPyramidPitch = 0.02;    // m, NOT cited (= base: the pyramids touch)
inline constexpr double kBackboardHeight = 7.0 * 0.0254;  // m: 7 in, the middle of the cited 6-8 in
// A dice tower's baffles (kind = "tower"): three ramps alternating sides at 40 deg, within the
// "three simple internal ramps at roughly 35 to 45 degrees" of a hobbyist's guide
// (visualfoodie.com/unique-and-creative-dice-tower-design-ideas); a typical design, not a standard.
inline constexpr int kTowerBaffles = 3;
inline constexpr double kTowerBaffleAngleDeg = 40.0;
inline constexpr double kTowerBaffleReach = 0.6;  // fraction of the chute's inner x width (NOT cited)

// One [[obstacles]] entry. Lengths in m, angles in degrees. "Local" axes are the obstacle's before
// `yaw_deg` turns it about the vertical through `centre`.
struct ObstacleDef {
  ObstacleKind kind = ObstacleKind::Plane;
  // Required: a [materials] key; its restitution and friction are the obstacle's against a die
  // (density and the rolling/pivoting resistances are unused).
  std::string material;
  // plane: the solid is {x : normal . x <= normal . point}; `normal` (stored unit, not zero) points
  // out of the wall into the free space.
  Vec3 point = Vec3::Zero(), normal = Vec3::UnitZ();
  // polyhedron: world corners (m); their convex hull is the obstacle (>= 4, not all in one plane).
  std::vector<Vec3> vertices;
  // box: its centre. tray, backboard, tower, cup: the middle of its foot (the floor is z = 0, so
  // centre z = 0 stands it on the floor); backboard: the middle of the foot of the face that
  // carries the pyramids.
  Vec3 centre = Vec3::Zero();
  // box: edge lengths (local x, y, z). tray: inner length (x), inner width (y), wall height (z).
  // tower: the chute's inner x and y widths and its height (z). Unused by the other kinds.
  Vec3 size = Vec3::Zero();
  double yaw_deg = 0.0;        // rotation about +z of the whole obstacle (box, tray, backboard, tower, cup)
  // tray, tower, cup: the walls' thickness (tower: also the baffles'); backboard: the board's behind
  // the pyramids (m), > 0.
  double thickness = 0.01;
  // backboard: the wall's length along its face (local y) and height (z); the pyramids cover the
  // face in a centred grid. cup: `height` is the wall height.
  double width = 0.0;
  double height = kBackboardHeight;
  double pyramid_base = kPyramidBase;      // backboard: edge of each pyramid's square base (on the face)
  double pyramid_height = kPyramidHeight;  // backboard: apex height above the face (toward local -x)
  double pyramid_pitch = kPyramidPitch;    // backboard: centre-to-centre spacing, along y and z (>= base)
  // tower: `baffles` inclined plates alternating sides (the lowest hangs from the -x wall and slopes
  // down toward the exit in the +x wall), each `baffle_angle_deg` below horizontal, covering
  // `baffle_reach` of the inner x width; the exit: an opening `exit_height` high at the foot of the
  // +x wall, the full inner y width wide.
  int baffles = kTowerBaffles;
  double baffle_angle_deg = kTowerBaffleAngleDeg;
  double baffle_reach = kTowerBaffleReach;
  double exit_height = 0.0;    // tower: read as size.z / 4 when the scene leaves it out
  // cup: a regular `sides`-gon ring of wall boxes; `radius` is the inner apothem (centre to each
  // wall's inner face), `height` the wall height.
  double radius = 0.0;
  int sides = 12;
};

struct SceneDef {
  std::string name;
  std::map<std::string, MaterialDef> materials;
  DieDef die;
  ThrowDef throw_;
  FloorDef floor;
  SimDef sim;
  // [[dice]]: 2 to 6 dice tossed together; empty: one die, `die`. A scene whose [[dice]] entries
  // all name other scenes may leave out [die]: `die` is then the first entry's die and `materials`
  // gains that die's materials.
  std::vector<DiceEntryDef> dice;
  std::vector<ObstacleDef> obstacles;  // [[obstacles]]: static obstacles
  OutcomesDef outcomes;                // [outcomes]: only with [[dice]]
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

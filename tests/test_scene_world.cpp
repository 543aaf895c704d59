// Several dice, obstacles and outcomes in a scene (issue 41): [[dice]], [[obstacles]], [outcomes],
// throw.hand, their errors, the hash of a scene whose dice name other scenes, and the convex pieces
// the obstacles expand into (sim/body/obstacles.hpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "sim/body/obstacles.hpp"
#include "sim/scene/key_unit.hpp"
#include "scene_test_util.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/scene/scene_hash.hpp"

namespace dicesim {
namespace {

namespace fs = std::filesystem;

using dicesim::testing::error_of;
using dicesim::testing::expect_contains;
using dicesim::testing::parse_error;
using dicesim::testing::TempDir;

// Every error names the file, the key, the value as written and what is allowed.
void expect_error(const SceneError& e, const std::string& file, const std::string& key, const std::string& value,
                  const std::string& allowed_part) {
  EXPECT_EQ(e.file(), file) << e.what();
  EXPECT_EQ(e.key(), key) << e.what();
  EXPECT_EQ(e.value(), value) << e.what();
  expect_contains(e.allowed(), allowed_part);
}

const std::string kWood = R"(
[materials.wood]
density = 700.0
restitution = 0.4
friction = 0.5
[materials.felt]
density = 300.0
restitution = 0.2
friction = 0.8
[die]
size = 0.016
material = "wood"
)";

// Two of this scene's own dice (entries without `scene`).
const std::string kTwo = kWood + R"(
[[dice]]
offset = [0.0, -0.02, 0.0]
[[dice]]
offset = [0.0, 0.02, 0.0]
)";

const std::string kD8 = R"(
[materials.bone]
density = 1900.0
restitution = 0.6
friction = 0.25
[die]
shape = "d8"
size = 0.018
material = "bone"
)";

// ---- [[dice]] -----------------------------------------------------------------------------------

TEST(SceneWorld, DiceEntriesTakeThisScenesDieOrAnothersWithTheirMaterialsAndOffsets) {
  TempDir dir;
  dir.write("dice/d8.toml", kD8);
  const std::string path = dir.write("two.toml", kWood + R"(
[[dice]]
offset = [0.01, -0.02, 0.03]
[[dice]]
scene = "dice/d8.toml"
offset = [0, 0.02, 0]
)");
  const SceneDef s = load_scene(path);
  ASSERT_EQ(s.dice.size(), 2u);
  EXPECT_EQ(s.dice[0].scene, "");
  EXPECT_EQ(s.dice[0].die.shape, ShapeKind::Box);
  EXPECT_EQ(s.dice[0].die.size, Vec3::Constant(0.016));
  EXPECT_EQ(s.dice[0].die.base_material, "wood");
  EXPECT_EQ(s.dice[0].materials.size(), 2u);
  EXPECT_EQ(s.dice[0].offset, Vec3(0.01, -0.02, 0.03));
  EXPECT_EQ(s.dice[1].scene, "dice/d8.toml");
  EXPECT_EQ(s.dice[1].die.shape, ShapeKind::D8);
  EXPECT_EQ(s.dice[1].die.size.x(), 0.018);
  EXPECT_EQ(s.dice[1].die.base_material, "bone");
  ASSERT_EQ(s.dice[1].materials.size(), 1u);
  EXPECT_EQ(s.dice[1].materials.at("bone").restitution, 0.6);
  EXPECT_EQ(s.dice[1].offset, Vec3(0, 0.02, 0));
  // The scene's own die is unchanged, and the defaults of what goes with [[dice]].
  EXPECT_EQ(s.die.shape, ShapeKind::Box);
  EXPECT_EQ(s.throw_.hand, HandKind::Each);
  EXPECT_EQ(s.outcomes.kind, OutcomeKind::Tuple);
  EXPECT_TRUE(s.obstacles.empty());
  EXPECT_EQ(key_unit("dice[1].offset"), "m");
  // One die: no dice entries.
  EXPECT_TRUE(parse_scene(kWood, "one.toml").dice.empty());
}

TEST(SceneWorld, HandAndOutcomesKinds) {
  const SceneDef shared = parse_scene(kTwo + "[throw]\nhand = \"shared\"\n[outcomes]\nkind = \"sum\"\n", "s.toml");
  EXPECT_EQ(shared.throw_.hand, HandKind::Shared);
  EXPECT_EQ(shared.outcomes.kind, OutcomeKind::Sum);
  const SceneDef each = parse_scene(kTwo + "[throw]\nhand = \"each\"\n[outcomes]\nkind = \"tuple\"\n", "s.toml");
  EXPECT_EQ(each.throw_.hand, HandKind::Each);
  EXPECT_EQ(each.outcomes.kind, OutcomeKind::Tuple);
}

// Without [die], the first entry's die stands for the scene's die, with its materials added.
TEST(SceneWorld, WithoutADieSectionTheFirstEntrysDieIsTheScenesDie) {
  TempDir dir;
  dir.write("d8.toml", kD8);
  dir.write("cube.toml", kWood);
  const std::string path = dir.write("pair.toml", R"(
[materials.felt]
restitution = 0.2
[[dice]]
scene = "d8.toml"
[[dice]]
scene = "cube.toml"
[[obstacles]]
kind = "plane"
material = "felt"
point = [0.5, 0, 0]
normal = [-1, 0, 0]
)");
  const SceneDef s = load_scene(path);
  ASSERT_EQ(s.dice.size(), 2u);
  EXPECT_EQ(s.die.shape, ShapeKind::D8);
  EXPECT_EQ(s.die.base_material, "bone");
  EXPECT_EQ(s.materials.count("bone"), 1u);
  EXPECT_EQ(s.materials.count("felt"), 1u);
  EXPECT_EQ(s.materials.count("wood"), 0u);  // only the first die's scene's materials
  EXPECT_EQ(s.dice[1].die.base_material, "wood");

  // A material of the same name defined differently: an error rather than a silent choice.
  const std::string clash = dir.write("clash.toml", "[materials.bone]\ndensity = 1.0\n[[dice]]\nscene = \"d8.toml\"\n"
                                                    "[[dice]]\nscene = \"cube.toml\"\n");
  expect_error(error_of([&] { load_scene(clash); }), clash, "dice[0].scene", "\"d8.toml\"",
               "defines material 'bone' unlike this scene's [materials.bone]");
}

TEST(SceneWorld, DiceCountAndOffsetErrors) {
  const std::string one = kWood + "[[dice]]\n";
  expect_error(parse_error(one), "mem.toml", "dice", "1 entry", "must have 2 to 6 entries (one die: use [die]");
  std::string seven = kWood;
  for (int i = 0; i < 7; ++i) seven += "[[dice]]\n";
  expect_error(parse_error(seven), "mem.toml", "dice", "7 entries", "must have 2 to 6 entries");
  expect_error(parse_error("dice = []\n" + kWood), "mem.toml", "dice", "0 entries", "must have 2 to 6 entries");
  expect_error(parse_error("dice = 3\n" + kWood), "mem.toml", "dice", "3", "must be an array of tables");

  const std::string bad_offset = kWood + "[[dice]]\n[[dice]]\noffset = [0.8, 0.8, 0]\n";
  expect_error(parse_error(bad_offset), "mem.toml", "dice[1].offset", "[0.8, 0.8, 0]", "length at most 1 m");
  expect_error(parse_error(kWood + "[[dice]]\noffset = [1.5, 0, 0]\n[[dice]]\n"), "mem.toml", "dice[0].offset[0]", "1.5",
               "must be a number in [-1, 1] m");
  expect_error(parse_error(kWood + "[[dice]]\noffset = [nan, 0, 0]\n[[dice]]\n"), "mem.toml", "dice[0].offset[0]", "nan",
               "must be finite");
  expect_error(parse_error(kWood + "[[dice]]\noffset = [0, 0]\n[[dice]]\n"), "mem.toml", "dice[0].offset", "[0, 0]",
               "must be an array of 3 numbers");
  expect_error(parse_error(kWood + "[[dice]]\nofset = [0, 0, 0]\n[[dice]]\n"), "mem.toml", "dice[0].ofset", "[0, 0, 0]",
               "unknown key 'ofset' in [dice[0]]; allowed: scene, offset");
}

TEST(SceneWorld, DiceSceneErrors) {
  TempDir dir;
  dir.write("coin.toml", "[materials.nickel]\ndensity = 8900.0\n[die]\nshape = \"cylinder\"\nradius = 0.012\nheight = 0.00175\n"
                         "material = \"nickel\"\n");
  dir.write("pair.toml", kTwo);
  dir.write("d8.toml", kD8);
  dir.write("broken.toml", "[materials.x]\ndensty = 1.0\n[die]\nmaterial = \"x\"\n");
  const std::string missing = dir.write("missing.toml", kWood + "[[dice]]\n[[dice]]\nscene = \"nowhere.toml\"\n");
  expect_error(error_of([&] { load_scene(missing); }), missing, "dice[1].scene", "\"nowhere.toml\"", "cannot open scene file");
  const std::string nested = dir.write("nested.toml", kWood + "[[dice]]\n[[dice]]\nscene = \"pair.toml\"\n");
  expect_error(error_of([&] { load_scene(nested); }), nested, "dice[1].scene", "\"pair.toml\"",
               "names a scene with [[dice]]");
  // An error inside the named scene names that scene's file.
  const std::string broken = dir.write("uses-broken.toml", kWood + "[[dice]]\n[[dice]]\nscene = \"broken.toml\"\n");
  const SceneError in_broken = error_of([&] { load_scene(broken); });
  EXPECT_EQ(in_broken.file(), (fs::path(broken).parent_path() / "broken.toml").string());
  EXPECT_EQ(in_broken.key(), "materials.x.densty");
  // An entry without `scene` in a scene without [die].
  const std::string no_die = dir.write("no-die.toml", "[[dice]]\nscene = \"d8.toml\"\n[[dice]]\n");
  const SceneError e = error_of([&] { load_scene(no_die); });
  EXPECT_EQ(e.file(), no_die);
  EXPECT_EQ(e.key(), "dice[1].scene");
  expect_contains(e.allowed(), "required: the path of a scene file");

  // Curved dice are refused among several dice and with obstacles.
  const std::string coin_entry = dir.write("coin-entry.toml", kWood + "[[dice]]\n[[dice]]\nscene = \"coin.toml\"\n");
  expect_error(error_of([&] { load_scene(coin_entry); }), coin_entry, "dice[1].scene", "\"coin.toml\"",
               "several dice and obstacles: polyhedral dice only");
  const std::string coin = "[materials.nickel]\n[die]\nshape = \"cylinder\"\nmaterial = \"nickel\"\n";
  expect_error(parse_error(coin + "[[dice]]\n[[dice]]\n"), "mem.toml", "die.shape", "\"cylinder\"",
               "several dice and obstacles: polyhedral dice only");
  expect_error(parse_error(coin + "[[obstacles]]\nkind = \"plane\"\nmaterial = \"nickel\"\nnormal = [0, 1, 0]\n"), "mem.toml",
               "die.shape", "\"cylinder\"", "several dice and obstacles: polyhedral dice only");
}

TEST(SceneWorld, HandAndOutcomesErrors) {
  expect_error(parse_error(kTwo + "[throw]\nhand = \"both\"\n"), "mem.toml", "throw.hand", "\"both\"",
               "must be one of: \"each\", \"shared\"");
  expect_error(parse_error(kWood + "[throw]\nhand = \"shared\"\n"), "mem.toml", "throw.hand", "\"shared\"",
               "applies only to a scene with [[dice]]");
  expect_error(parse_error(kTwo + "[outcomes]\nkind = \"product\"\n"), "mem.toml", "outcomes.kind", "\"product\"",
               "must be one of: \"tuple\", \"sum\"");
  expect_error(parse_error(kWood + "[outcomes]\nkind = \"sum\"\n"), "mem.toml", "outcomes", "{kind = \"sum\"}",
               "applies only to a scene with [[dice]]");
  expect_error(parse_error(kTwo + "[outcomes]\nkinds = \"sum\"\n"), "mem.toml", "outcomes.kinds", "\"sum\"",
               "unknown key 'kinds' in [outcomes]; allowed: kind");
}

// Overrides reach an entry by its index in brackets (the existing mechanism); "dice.0" is not a path.
TEST(SceneWorld, OverridesReachADiceEntryByIndex) {
  const SceneDef s = parse_scene(kTwo, "s.toml", {"dice[1].offset=[0.1, 0, 0.05]", "throw.hand=shared"});
  EXPECT_EQ(s.dice[1].offset, Vec3(0.1, 0, 0.05));
  EXPECT_EQ(s.dice[0].offset, Vec3(0, -0.02, 0));
  EXPECT_EQ(s.throw_.hand, HandKind::Shared);
  const SceneError beyond = parse_error(kTwo, {"dice[2].offset=[0, 0, 0]"});
  EXPECT_EQ(beyond.file(), "mem.toml (--set)");
  EXPECT_EQ(beyond.allowed(), "index 2 is out of range: dice has 2 elements (indices 0 to 1)");
  const SceneError dotted = parse_error(kTwo, {"dice.0.offset=[0, 0, 0]"});
  EXPECT_EQ(dotted.key(), "dice");
  expect_contains(dotted.allowed(), "must be an array of tables");
}

TEST(SceneWorld, HashFollowsTheContentOfTheDieScenesItNames) {
  TempDir dir;
  const std::string d8 = dir.write("d8.toml", kD8);
  dir.write("other/d8-copy.toml", kD8);
  const std::string a = dir.write("a.toml", kWood + "[[dice]]\n[[dice]]\nscene = \"d8.toml\"\n");
  const std::string b = dir.write("b.toml", kWood + "[[dice]]\n[[dice]]\nscene = \"other/d8-copy.toml\"\n");
  const std::string before = scene_sha256(a);
  EXPECT_EQ(scene_sha256(a), before);
  EXPECT_EQ(scene_sha256(b), before);  // the same die under another path
  dir.write("d8.toml", kD8 + "rounding = 0.001\n");
  const std::string after = scene_sha256(a);
  EXPECT_NE(after, before);
  EXPECT_EQ(scene_sha256(b), before);  // b's die did not change
  // A change that reaches the named scene through its own `extends` counts too.
  dir.write("base.toml", kD8);
  dir.write("d8.toml", "extends = \"base.toml\"\n");
  const std::string via_base = scene_sha256(a);
  EXPECT_EQ(via_base, before);
  std::string rougher = kD8;
  rougher.replace(rougher.find("friction = 0.25"), 15, "friction = 0.35");
  dir.write("base.toml", rougher);
  EXPECT_NE(scene_sha256(a), via_base);
  (void)d8;
}

// ---- [[obstacles]] -----------------------------------------------------------------------------

TEST(SceneWorld, EveryObstacleKindIsReadWithItsDefaults) {
  const SceneDef s = parse_scene(kWood + R"(
[[obstacles]]
kind = "plane"
material = "felt"
point = [0.5, 0, 0]
normal = [-2, 0, 0]
[[obstacles]]
kind = "polyhedron"
material = "wood"
vertices = [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]
[[obstacles]]
kind = "box"
material = "wood"
centre = [0.3, 0.1, 0.05]
size = [0.1, 0.2, 0.1]
yaw_deg = 30
[[obstacles]]
kind = "tray"
material = "felt"
size = [0.4, 0.3, 0.05]
[[obstacles]]
kind = "backboard"
material = "felt"
centre = [0.8, 0, 0]
width = 1.2
[[obstacles]]
kind = "tower"
material = "wood"
size = [0.09, 0.09, 0.25]
[[obstacles]]
kind = "cup"
material = "felt"
radius = 0.05
height = 0.08
)", "obstacles.toml");
  ASSERT_EQ(s.obstacles.size(), 7u);
  const ObstacleDef& plane = s.obstacles[0];
  EXPECT_EQ(plane.kind, ObstacleKind::Plane);
  EXPECT_EQ(plane.material, "felt");
  EXPECT_EQ(plane.point, Vec3(0.5, 0, 0));
  EXPECT_EQ(plane.normal, Vec3(-1, 0, 0));  // normalised
  const ObstacleDef& poly = s.obstacles[1];
  EXPECT_EQ(poly.kind, ObstacleKind::Polyhedron);
  ASSERT_EQ(poly.vertices.size(), 4u);
  EXPECT_EQ(poly.vertices[3], Vec3(0, 0, 0.1));
  const ObstacleDef& box = s.obstacles[2];
  EXPECT_EQ(box.kind, ObstacleKind::Box);
  EXPECT_EQ(box.centre, Vec3(0.3, 0.1, 0.05));
  EXPECT_EQ(box.size, Vec3(0.1, 0.2, 0.1));
  EXPECT_EQ(box.yaw_deg, 30.0);
  const ObstacleDef& tray = s.obstacles[3];
  EXPECT_EQ(tray.kind, ObstacleKind::Tray);
  EXPECT_EQ(tray.size, Vec3(0.4, 0.3, 0.05));
  EXPECT_EQ(tray.thickness, 0.01);
  EXPECT_EQ(tray.centre, Vec3::Zero());
  const ObstacleDef& board = s.obstacles[4];
  EXPECT_EQ(board.kind, ObstacleKind::Backboard);
  EXPECT_EQ(board.width, 1.2);
  EXPECT_DOUBLE_EQ(board.height, 7 * 0.0254);
  EXPECT_EQ(board.pyramid_base, kPyramidBase);
  EXPECT_EQ(board.pyramid_height, kPyramidHeight);
  EXPECT_EQ(board.pyramid_pitch, kPyramidPitch);
  const ObstacleDef& tower = s.obstacles[5];
  EXPECT_EQ(tower.kind, ObstacleKind::Tower);
  EXPECT_EQ(tower.baffles, 3);
  EXPECT_EQ(tower.baffle_angle_deg, 40.0);
  EXPECT_EQ(tower.baffle_reach, 0.6);
  EXPECT_DOUBLE_EQ(tower.exit_height, 0.25 / 4);
  const ObstacleDef& cup = s.obstacles[6];
  EXPECT_EQ(cup.kind, ObstacleKind::Cup);
  EXPECT_EQ(cup.radius, 0.05);
  EXPECT_EQ(cup.height, 0.08);
  EXPECT_EQ(cup.sides, 12);
  EXPECT_EQ(key_unit("obstacles[3].size"), "m");
  EXPECT_EQ(key_unit("obstacles[5].baffle_angle_deg"), "deg");
}

TEST(SceneWorld, ObstacleErrors) {
  const std::string head = kWood + "[[obstacles]]\n";
  auto err = [&](const std::string& keys) { return parse_error(head + keys); };
  expect_error(err("material = \"felt\"\n"), "mem.toml", "obstacles[0].kind", "", "required: one of: \"plane\", \"polyhedron\"");
  expect_error(err("kind = \"wall\"\nmaterial = \"felt\"\n"), "mem.toml", "obstacles[0].kind", "\"wall\"",
               "must be one of: \"plane\", \"polyhedron\", \"box\", \"tray\", \"backboard\", \"tower\", \"cup\"");
  expect_error(err("kind = \"plane\"\nnormal = [0, 0, 1]\n"), "mem.toml", "obstacles[0].material", "",
               "required: the name of a material; defined: felt, wood");
  expect_error(err("kind = \"plane\"\nmaterial = \"rubber\"\nnormal = [0, 0, 1]\n"), "mem.toml", "obstacles[0].material",
               "\"rubber\"", "must name a material in [materials]; defined: felt, wood");
  expect_error(err("kind = \"plane\"\nmaterial = \"felt\"\nnormal = [0, 0, 0]\n"), "mem.toml", "obstacles[0].normal",
               "[0, 0, 0]", "not all 0");
  expect_error(err("kind = \"plane\"\nmaterial = \"felt\"\n"), "mem.toml", "obstacles[0].normal", "", "required: an array of 3 numbers");
  expect_error(err("kind = \"polyhedron\"\nmaterial = \"felt\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\n"), "mem.toml",
               "obstacles[0].vertices", "[[0, 0, 0], [1, 0, 0], [0, 1, 0]]", "at least 4 points");
  expect_error(err("kind = \"polyhedron\"\nmaterial = \"felt\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]\n"),
               "mem.toml", "obstacles[0].vertices", "[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]", "lie in one plane");
  expect_error(err("kind = \"box\"\nmaterial = \"felt\"\nsize = [0.1, 0, 0.1]\n"), "mem.toml", "obstacles[0].size[1]", "0",
               "must be a number in (0, 100] m");
  expect_error(err("kind = \"box\"\nmaterial = \"felt\"\n"), "mem.toml", "obstacles[0].size", "",
               "required: edge lengths: an array of 3 numbers, each in (0, 100] m (kind = \"box\")");
  expect_error(err("kind = \"tray\"\nmaterial = \"felt\"\nsize = [0.4, 0.3, 0.05]\nthickness = -0.01\n"), "mem.toml",
               "obstacles[0].thickness", "-0.01", "must be a number in (0, 100] m");
  expect_error(err("kind = \"box\"\nmaterial = \"felt\"\nsize = [1, 1, 1]\nnormal = [0, 0, 1]\n"), "mem.toml",
               "obstacles[0].normal", "[0, 0, 1]", "does not apply to kind = \"box\"; it is for kind \"plane\"");
  expect_error(err("kind = \"plane\"\nmaterial = \"felt\"\nnormal = [0, 0, 1]\nyaw_deg = 10\n"), "mem.toml",
               "obstacles[0].yaw_deg", "10", "does not apply to kind = \"plane\"");
  expect_error(err("kind = \"box\"\nmaterial = \"felt\"\nsize = [1, 1, 1]\ncolour = \"red\"\n"), "mem.toml",
               "obstacles[0].colour", "\"red\"", "unknown key 'colour' in [obstacles[0]]");
  // Backboard: the pyramids must fit on the face and not overlap.
  expect_error(err("kind = \"backboard\"\nmaterial = \"felt\"\nwidth = 1.0\nheight = 0.01\n"), "mem.toml",
               "obstacles[0].pyramid_base", "", "at least one pyramid must fit on the face");
  expect_error(err("kind = \"backboard\"\nmaterial = \"felt\"\nwidth = 1.0\npyramid_pitch = 0.015\n"), "mem.toml",
               "obstacles[0].pyramid_pitch", "0.015", "must be a number >= pyramid_base = 0.02 m");
  expect_error(err("kind = \"backboard\"\nmaterial = \"felt\"\n"), "mem.toml", "obstacles[0].width", "", "required: the wall's length");
  // Tower: the baffles must fit in its height, the exit in its foot.
  expect_error(err("kind = \"tower\"\nmaterial = \"felt\"\nsize = [0.09, 0.09, 0.25]\nbaffle_angle_deg = 89\n"), "mem.toml",
               "obstacles[0].baffle_angle_deg", "89", "the baffles do not fit");
  expect_error(err("kind = \"tower\"\nmaterial = \"felt\"\nsize = [0.09, 0.09, 0.25]\nbaffle_angle_deg = 90\n"), "mem.toml",
               "obstacles[0].baffle_angle_deg", "90", "must be a number in (0, 90) deg");
  expect_error(err("kind = \"tower\"\nmaterial = \"felt\"\nsize = [0.09, 0.09, 0.25]\nexit_height = 0.3\n"), "mem.toml",
               "obstacles[0].exit_height", "0.3", "must be a number in (0, size.z) = (0, 0.25) m");
  expect_error(err("kind = \"tower\"\nmaterial = \"felt\"\nsize = [0.09, 0.09, 0.25]\nbaffle_reach = 1.5\n"), "mem.toml",
               "obstacles[0].baffle_reach", "1.5", "must be a number in (0, 1]");
  // Cup.
  expect_error(err("kind = \"cup\"\nmaterial = \"felt\"\nradius = 0.05\nheight = 0.08\nsides = 2\n"), "mem.toml",
               "obstacles[0].sides", "2", "must be an integer in [3, 360]");
  expect_error(err("kind = \"cup\"\nmaterial = \"felt\"\nheight = 0.08\n"), "mem.toml", "obstacles[0].radius", "",
               "required: the inner radius");
  // The file named is the one the value was written in: here an override.
  const SceneError set = parse_error(head + "kind = \"box\"\nmaterial = \"felt\"\nsize = [1, 1, 1]\n", {"obstacles[0].size[2]=-1"});
  expect_error(set, "mem.toml (--set)", "obstacles[0].size[2]", "-1", "must be a number in (0, 100] m");
}

// ---- obstacle_pieces ---------------------------------------------------------------------------

// Signed distance-like test: the largest n.(x - p) over the piece's faces (<= 0: x is in the piece).
double outside_by(const ObstaclePiece& p, const Vec3& x) {
  if (p.plane) return p.normal.dot(x) - p.offset;
  double worst = -1e300;
  for (std::size_t f = 0; f < p.face_normals.size(); ++f) worst = std::max(worst, p.face_normals[f].dot(x - p.face_points[f]));
  return worst;
}

// Every polyhedron piece: unit outward normals (each corner on or behind every face plane, within
// 1e-12 m; each face plane has at least 3 corners on it), unit edge directions, corners that are
// all hull vertices.
void expect_convex_and_outward(const std::vector<ObstaclePiece>& pieces) {
  for (const ObstaclePiece& p : pieces) {
    SCOPED_TRACE(p.name);
    if (p.plane) {
      EXPECT_NEAR(p.normal.norm(), 1.0, 1e-15);
      continue;
    }
    ASSERT_EQ(p.face_normals.size(), p.face_points.size());
    ASSERT_GE(p.face_normals.size(), 4u);
    for (std::size_t f = 0; f < p.face_normals.size(); ++f) {
      EXPECT_NEAR(p.face_normals[f].norm(), 1.0, 1e-14);
      int on = 0;
      for (const Vec3& c : p.corners) {
        const double d = p.face_normals[f].dot(c - p.face_points[f]);
        EXPECT_LE(d, 1e-12) << "corner " << c.transpose() << " outside face " << f;
        on += std::abs(d) <= 1e-12;
      }
      EXPECT_GE(on, 3) << "face " << f;
    }
    for (const Vec3& e : p.edge_dirs) EXPECT_NEAR(e.norm(), 1.0, 1e-14);
    // Each corner lies on at least 3 faces: a vertex of the hull, not a point inside a face or edge.
    for (const Vec3& c : p.corners) {
      int faces = 0;
      for (std::size_t f = 0; f < p.face_normals.size(); ++f) faces += std::abs(p.face_normals[f].dot(c - p.face_points[f])) <= 1e-12;
      EXPECT_GE(faces, 3) << "corner " << c.transpose();
    }
  }
}

const ObstaclePiece* piece_containing(const std::vector<ObstaclePiece>& pieces, const Vec3& x, double margin = 1e-9) {
  for (const ObstaclePiece& p : pieces)
    if (outside_by(p, x) < -margin) return &p;
  return nullptr;
}

TEST(SceneWorld, TrayWallsEncloseTheInnerRectangle) {
  for (const double yaw : {0.0, 30.0, -135.0}) {
    SCOPED_TRACE("yaw " + std::to_string(yaw));
    const Vec3 centre(0.2, -0.1, 0.0);
    const SceneDef s = parse_scene(kWood + "[[obstacles]]\nkind = \"tray\"\nmaterial = \"felt\"\ncentre = [0.2, -0.1, 0]\n"
                                           "size = [0.4, 0.3, 0.05]\nthickness = 0.02\nyaw_deg = " + std::to_string(yaw) + "\n",
                                   "tray.toml");
    const std::vector<ObstaclePiece> pieces = obstacle_pieces(s);
    ASSERT_EQ(pieces.size(), 4u);
    expect_convex_and_outward(pieces);
    EXPECT_EQ(pieces[0].name, "obstacles[0] tray wall +x");
    for (const ObstaclePiece& p : pieces) {
      EXPECT_EQ(p.restitution, 0.2);
      EXPECT_EQ(p.friction, 0.8);
      EXPECT_EQ(p.material, "felt");
      EXPECT_EQ(p.corners.size(), 8u);
      EXPECT_EQ(p.edge_dirs.size(), 3u);
    }
    const Mat3 r = rot_z(yaw * kPi / 180.0);
    auto world = [&](double x, double y, double z) { return Vec3(centre + r * Vec3(x, y, z)); };
    // Points inside the inner rectangle, up to its walls' inner faces: in no piece.
    for (const double x : {-0.199, -0.1, 0.0, 0.15, 0.199})
      for (const double y : {-0.149, 0.0, 0.149})
        for (const double z : {0.001, 0.025, 0.049})
          EXPECT_EQ(piece_containing(pieces, world(x, y, z)), nullptr) << x << " " << y << " " << z;
    // Points in each wall and in the corners: in one piece.
    for (const Vec3& in_wall : {world(0.21, 0, 0.02), world(-0.21, 0.1, 0.02), world(0.1, 0.16, 0.04), world(-0.1, -0.16, 0.01),
                                world(0.215, 0.165, 0.02), world(-0.215, -0.165, 0.02)})
      EXPECT_NE(piece_containing(pieces, in_wall), nullptr) << in_wall.transpose();
    // Outside and above: free.
    EXPECT_EQ(piece_containing(pieces, world(0.23, 0, 0.02)), nullptr);
    EXPECT_EQ(piece_containing(pieces, world(0.21, 0, 0.051)), nullptr);
  }
}

TEST(SceneWorld, BackboardPyramidsLieOnTheWallsFace) {
  for (const double yaw : {0.0, 90.0, 200.0}) {
    SCOPED_TRACE("yaw " + std::to_string(yaw));
    const SceneDef s = parse_scene(kWood + "[[obstacles]]\nkind = \"backboard\"\nmaterial = \"felt\"\ncentre = [0.8, 0.1, 0]\n"
                                           "width = 0.3\nheight = 0.1\npyramid_base = 0.02\npyramid_height = 0.012\n"
                                           "pyramid_pitch = 0.025\nyaw_deg = " + std::to_string(yaw) + "\n",
                                   "board.toml");
    const std::vector<ObstaclePiece> pieces = obstacle_pieces(s);
    expect_convex_and_outward(pieces);
    // The board, then a grid: floor((0.3 - 0.02) / 0.025) + 1 = 12 columns, floor((0.1 - 0.02) / 0.025) + 1 = 4 rows.
    ASSERT_EQ(pieces.size(), 1u + 12u * 4u);
    EXPECT_EQ(pieces[0].name, "obstacles[0] backboard board");
    EXPECT_EQ(pieces[1].name, "obstacles[0] backboard pyramid row 0 column 0");
    const Mat3 r = rot_z(yaw * kPi / 180.0);
    const Vec3 centre(0.8, 0.1, 0), face_normal = r * Vec3(-1, 0, 0), along = r * Vec3(0, 1, 0);
    // The board's face toward the thrower is the plane through `centre` normal to face_normal.
    const ObstaclePiece& board = pieces[0];
    bool has_face = false;
    for (std::size_t f = 0; f < board.face_normals.size(); ++f)
      has_face = has_face || ((board.face_normals[f] - face_normal).norm() < 1e-12 &&
                              std::abs(face_normal.dot(board.face_points[f] - centre)) < 1e-12);
    EXPECT_TRUE(has_face);
    std::set<std::pair<long, long>> cells;
    for (std::size_t k = 1; k < pieces.size(); ++k) {
      const ObstaclePiece& p = pieces[k];
      SCOPED_TRACE(p.name);
      ASSERT_EQ(p.corners.size(), 5u);
      EXPECT_EQ(p.face_normals.size(), 5u);
      int on_face = 0;
      Vec3 apex = Vec3::Zero();
      Vec3 base_centre = Vec3::Zero();
      for (const Vec3& c : p.corners) {
        const double out = face_normal.dot(c - centre);
        if (std::abs(out) < 1e-12) {
          ++on_face;
          base_centre += c / 4.0;
          // On the face's rectangle: |along| <= width/2, 0 <= z <= height.
          EXPECT_LE(std::abs(along.dot(c - centre)), 0.15 + 1e-12);
          EXPECT_GE(c.z(), -1e-12);
          EXPECT_LE(c.z(), 0.1 + 1e-12);
        } else {
          EXPECT_NEAR(out, 0.012, 1e-12);  // the apex, in front of the face
          apex = c;
        }
      }
      EXPECT_EQ(on_face, 4);
      EXPECT_LT((apex - base_centre - 0.012 * face_normal).norm(), 1e-12);
      // Base edges: 0.02 along the face (a square).
      EXPECT_NEAR((p.corners[1] - p.corners[0]).norm(), 0.02, 1e-12);
      EXPECT_NEAR((p.corners[3] - p.corners[0]).norm(), 0.02, 1e-12);
      // The grid: pitch 0.025, centred; distinct cells.
      const double u = along.dot(base_centre - centre) / 0.025 + 5.5, v = (base_centre.z() - 0.05) / 0.025 + 1.5;
      EXPECT_NEAR(u, std::round(u), 1e-9);
      EXPECT_NEAR(v, std::round(v), 1e-9);
      cells.insert({std::lround(u), std::lround(v)});
    }
    EXPECT_EQ(cells.size(), 48u);
  }
}

TEST(SceneWorld, EveryPolyhedronPiecesFaceNormalsAreOutward) {
  const SceneDef s = parse_scene(kWood + R"(
[[obstacles]]
kind = "polyhedron"
material = "wood"
vertices = [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1], [0.02, 0.02, 0.02], [0.1, 0.1, 0.1]]
[[obstacles]]
kind = "box"
material = "wood"
centre = [0.3, 0.1, 0.05]
size = [0.1, 0.2, 0.1]
yaw_deg = 30
[[obstacles]]
kind = "tower"
material = "wood"
centre = [-0.3, 0.2, 0]
size = [0.09, 0.08, 0.25]
yaw_deg = 75
[[obstacles]]
kind = "cup"
material = "felt"
centre = [0, -0.4, 0]
radius = 0.05
height = 0.08
sides = 12
yaw_deg = 7
[[obstacles]]
kind = "plane"
material = "felt"
point = [0.5, 0, 0]
normal = [-1, -1, 0]
)", "all.toml");
  const std::vector<ObstaclePiece> pieces = obstacle_pieces(s);
  // 1 polyhedron + 1 box + 4 tower walls + 3 baffles + 12 cup walls + 1 plane.
  ASSERT_EQ(pieces.size(), 1u + 1u + 7u + 12u + 1u);
  expect_convex_and_outward(pieces);
  // The polyhedron is the hull: the interior point (0.02, 0.02, 0.02) is not a corner.
  EXPECT_EQ(pieces[0].corners.size(), 5u);
  EXPECT_EQ(pieces[0].name, "obstacles[0] polyhedron");
  EXPECT_EQ(pieces[0].restitution, 0.4);
  // The plane: unit normal, offset n . point.
  const ObstaclePiece& plane = pieces.back();
  EXPECT_TRUE(plane.plane);
  EXPECT_LT((plane.normal - Vec3(-1, -1, 0).normalized()).norm(), 1e-15);
  EXPECT_NEAR(plane.offset, -0.5 / std::sqrt(2.0), 1e-15);
  EXPECT_LT(outside_by(plane, Vec3(1, 0, 0)), 0.0);  // behind the wall: in the solid
  EXPECT_GT(outside_by(plane, Vec3(0, 0, 0)), 0.0);  // the free side
}

TEST(SceneWorld, TowerIsAChuteWithBafflesAndAnExitAndTheCupIsClosed) {
  const SceneDef s = parse_scene(kWood + R"(
[[obstacles]]
kind = "tower"
material = "wood"
size = [0.09, 0.08, 0.25]
thickness = 0.005
[[obstacles]]
kind = "cup"
material = "felt"
centre = [1, 0, 0]
radius = 0.05
height = 0.08
sides = 8
thickness = 0.004
)", "tower.toml");
  const std::vector<ObstaclePiece> pieces = obstacle_pieces(s);
  ASSERT_EQ(pieces.size(), 7u + 8u);
  expect_convex_and_outward(pieces);
  const std::vector<ObstaclePiece> tower(pieces.begin(), pieces.begin() + 7);
  EXPECT_EQ(tower[1].name, "obstacles[0] tower wall +x (above the exit)");
  EXPECT_EQ(tower[4].name, "obstacles[0] tower baffle 0");
  // The exit: at the foot of the +x wall, below exit_height = 0.25 / 4, free; above it, wall.
  EXPECT_EQ(piece_containing(tower, Vec3(0.0475, 0, 0.03)), nullptr);
  EXPECT_NE(piece_containing(tower, Vec3(0.0475, 0, 0.07)), nullptr);
  EXPECT_NE(piece_containing(tower, Vec3(-0.0475, 0, 0.03)), nullptr);  // the -x wall is closed
  EXPECT_NE(piece_containing(tower, Vec3(0, 0.0425, 0.1)), nullptr);
  // Baffles alternate: seen from above, a point near either inner x wall is under some baffle, and
  // a vertical line through the chute meets at least one baffle (no straight fall).
  const std::vector<ObstaclePiece> baffles(tower.begin() + 4, tower.end());
  for (const double x : {-0.044, -0.02, 0.0, 0.02, 0.044}) {
    int hits = 0;
    for (double z = 0.0005; z < 0.25; z += 0.0005) hits += piece_containing(baffles, Vec3(x, 0.01, z)) != nullptr;
    EXPECT_GT(hits, 0) << "x = " << x;
  }
  // The lowest baffle hangs from the -x wall and slopes down toward the exit (+x).
  const ObstaclePiece& lowest = tower[4];
  double zmax_at_minus = -1, zmin_at_plus = 1;
  for (const Vec3& c : lowest.corners) {
    if (c.x() < -0.04) zmax_at_minus = std::max(zmax_at_minus, c.z());
    if (c.x() > -0.01) zmin_at_plus = std::min(zmin_at_plus, c.z());
  }
  EXPECT_GT(zmax_at_minus, zmin_at_plus);
  // The cup: a closed ring. In every direction, the point midway through the ring (between the
  // inner and outer octagons) is in a wall, also at the corners; inside the inner octagon is free.
  const std::vector<ObstaclePiece> cup(pieces.begin() + 7, pieces.end());
  for (int k = 0; k < 720; ++k) {
    const double a = 2 * kPi * k / 720, sector = 2 * kPi / 8;
    const double off = a - std::round(a / sector) * sector;  // from the nearest wall's normal
    const Vec3 dir(std::cos(a), std::sin(a), 0);
    EXPECT_NE(piece_containing(cup, Vec3(1, 0, 0.04) + (0.052 / std::cos(off)) * dir), nullptr) << a;
    EXPECT_EQ(piece_containing(cup, Vec3(1, 0, 0.04) + 0.0499 * dir), nullptr) << a;
  }
}

}  // namespace
}  // namespace dicesim

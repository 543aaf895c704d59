// Scene loading: ready scenes, defaults, extends, --set overrides, and every class of error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "sim/models/compile.hpp"
#include "scene_test_util.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim {
namespace {

namespace fs = std::filesystem;

const std::string kScenes = std::string(DICESIM_SOURCE_DIR) + "/scenes/";
const std::string kDie1 = kScenes + "paper/die1.toml";

// Minimal valid scene text: everything else is default.
const std::string kMinimal = R"(
[materials.wood]
density = 700.0
[die]
material = "wood"
)";

using dicesim::testing::error_of;
using dicesim::testing::expect_contains;
using dicesim::testing::parse_error;
using dicesim::testing::TempDir;

// ---- ready scenes -------------------------------------------------------------------------------

void expect_paper_materials(const SceneDef& s) {
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_DOUBLE_EQ(s.materials.at("steel").density, 7848.0);
  EXPECT_DOUBLE_EQ(s.materials.at("aluminium").density, 2714.3);
  EXPECT_DOUBLE_EQ(s.materials.at("steel").restitution, 0.487);
  EXPECT_DOUBLE_EQ(s.materials.at("aluminium").restitution, 0.550);
  EXPECT_DOUBLE_EQ(s.materials.at("steel").friction, 0.3);
  EXPECT_DOUBLE_EQ(s.materials.at("aluminium").friction, 0.3);
  EXPECT_EQ(s.die.size, Vec3::Constant(0.03));
  EXPECT_EQ(s.die.base_material, "aluminium");
  EXPECT_EQ(s.sim.fidelity, Fidelity::Paper);
  EXPECT_DOUBLE_EQ(s.sim.stop_speed, 0.1);
}

void expect_default_throw(const ThrowDef& t) {
  EXPECT_EQ(t.orientation.kind, OrientationKind::Uniform);
  EXPECT_DOUBLE_EQ(t.height.mean, 1.0);
  EXPECT_DOUBLE_EQ(t.height.sd, 0.2);
  EXPECT_EQ(t.velocity.mean, Vec3::Zero());
  EXPECT_EQ(t.velocity.sd, Vec3::Constant(0.5));
  EXPECT_EQ(t.spin.kind, SpinKind::Normal);
  EXPECT_EQ(t.spin.components.mean, Vec3::Zero());
  EXPECT_EQ(t.spin.components.sd, Vec3::Constant(18.0));
}

void expect_one_cut(const SceneDef& s, const Vec3& normal, double offset) {
  ASSERT_EQ(s.die.regions.size(), 1u);
  EXPECT_EQ(s.die.regions[0].material, "steel");
  ASSERT_EQ(s.die.regions[0].half_spaces.size(), 1u);
  EXPECT_EQ(s.die.regions[0].half_spaces[0].normal, normal);
  EXPECT_DOUBLE_EQ(s.die.regions[0].half_spaces[0].offset, offset);
}

TEST(SceneReady, Die1) {
  const SceneDef s = load_scene(kDie1);
  EXPECT_EQ(s.name, "die1");
  expect_paper_materials(s);
  expect_default_throw(s.throw_);
  expect_one_cut(s, Vec3(0, 0, -1), 0.0);
  EXPECT_EQ(s.die.face_labels, (std::array<int, 6>{2, 5, 3, 4, 1, 6}));
  EXPECT_FALSE(s.floor.restitution.has_value());
}

TEST(SceneReady, Die2) {
  const SceneDef s = load_scene(kScenes + "paper/die2.toml");
  expect_paper_materials(s);
  expect_default_throw(s.throw_);
  expect_one_cut(s, Vec3(0, 0, -1), 0.009);
  EXPECT_EQ(s.die.face_labels, (std::array<int, 6>{2, 5, 3, 4, 1, 6}));
}

TEST(SceneReady, Die3) {
  const SceneDef s = load_scene(kScenes + "paper/die3.toml");
  expect_paper_materials(s);
  expect_default_throw(s.throw_);
  expect_one_cut(s, Vec3(-1, 0, 1), 0.0);
  // +x, -x, +y, -y, +z, -z: +x and -z all steel (5, 6), -x and +z all aluminium (2, 1).
  EXPECT_EQ(s.die.face_labels, (std::array<int, 6>{5, 2, 3, 4, 1, 6}));
}

TEST(SceneReady, Fair) {
  const SceneDef s = load_scene(kScenes + "fair.toml");
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.die.base_material, "plastic");
  EXPECT_TRUE(s.die.regions.empty());
  EXPECT_EQ(s.die.size, Vec3::Constant(0.03));
  expect_default_throw(s.throw_);
}

TEST(SceneReady, SwappedRestitutionVariant) {
  const SceneDef s = load_scene(kScenes + "paper/variants/die1-seed-swapped-restitution.toml");
  EXPECT_EQ(s.name, "die1-seed-swapped-restitution");
  EXPECT_DOUBLE_EQ(s.materials.at("steel").restitution, 0.55);
  EXPECT_DOUBLE_EQ(s.materials.at("aluminium").restitution, 0.49);
  EXPECT_DOUBLE_EQ(s.materials.at("steel").density, 7848.0);  // inherited
  expect_one_cut(s, Vec3(0, 0, -1), 0.0);
}

TEST(SceneReady, VarianceReadingVariant) {
  const SceneDef s = load_scene(kScenes + "paper/variants/die1-seed-variance-reading.toml");
  EXPECT_NEAR(s.throw_.height.sd, std::sqrt(0.2), 1e-9);
  EXPECT_NEAR(s.throw_.velocity.sd.x(), std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(s.throw_.velocity.sd.z(), std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(s.throw_.spin.components.sd.y(), std::sqrt(18.0), 1e-9);
  EXPECT_DOUBLE_EQ(s.throw_.height.mean, 1.0);
  expect_paper_materials(s);
}

TEST(SceneReady, EulerUniformVariant) {
  const SceneDef s = load_scene(kScenes + "paper/variants/die1-seed-euler-uniform.toml");
  EXPECT_EQ(s.throw_.orientation.kind, OrientationKind::EulerUniform);
  expect_paper_materials(s);
}

// ---- defaults -----------------------------------------------------------------------------------

TEST(SceneDefaults, MinimalSceneGetsEveryDefault) {
  const SceneDef s = parse_scene(kMinimal, "dir/minimal.toml");
  const SceneDef d = default_scene_def();
  EXPECT_EQ(s.name, "minimal");
  EXPECT_DOUBLE_EQ(s.materials.at("wood").density, 700.0);
  EXPECT_DOUBLE_EQ(s.materials.at("wood").restitution, MaterialDef{}.restitution);
  EXPECT_DOUBLE_EQ(s.materials.at("wood").friction, MaterialDef{}.friction);
  EXPECT_EQ(s.die.size, d.die.size);
  EXPECT_EQ(s.die.face_labels, d.die.face_labels);
  EXPECT_TRUE(s.die.regions.empty());
  expect_default_throw(s.throw_);
  EXPECT_EQ(s.throw_.orientation.euler_deg, d.throw_.orientation.euler_deg);
  EXPECT_EQ(s.sim.fidelity, Fidelity::Auto);  // a file that names no model runs auto (scenes built in code: paper)
  EXPECT_DOUBLE_EQ(s.sim.gravity, 9.81);
  EXPECT_DOUBLE_EQ(s.sim.stop_speed, 0.1);
  EXPECT_EQ(s.sim.max_bounces, 1000);
  EXPECT_DOUBLE_EQ(s.sim.max_time, 60.0);
  EXPECT_FALSE(s.floor.restitution.has_value());
}

TEST(SceneDefaults, ThrowKindsAndShorthands) {
  const SceneDef s = parse_scene(kMinimal + R"(
[die.faces]
"+z" = 6
"-z" = 1
[throw.orientation]
kind = "fixed"
euler_deg = [10, 20, 30]
[throw.height]
kind = "fixed"
mean = 0.5
[throw.velocity]
mean = [1, 2, 3]
sd = 0
[throw.spin]
kind = "random-axis"
mean = 30
sd = 5
[floor]
restitution = 0.25
[sim]
max_bounces = 7
)", "x");
  EXPECT_EQ(s.die.face_labels, (std::array<int, 6>{2, 5, 3, 4, 6, 1}));
  EXPECT_EQ(s.throw_.orientation.kind, OrientationKind::Fixed);
  EXPECT_EQ(s.throw_.orientation.euler_deg, Vec3(10, 20, 30));
  EXPECT_DOUBLE_EQ(s.throw_.height.mean, 0.5);
  EXPECT_DOUBLE_EQ(s.throw_.height.sd, 0.0);
  EXPECT_EQ(s.throw_.velocity.mean, Vec3(1, 2, 3));
  EXPECT_EQ(s.throw_.velocity.sd, Vec3::Zero());
  EXPECT_EQ(s.throw_.spin.kind, SpinKind::RandomAxis);
  EXPECT_DOUBLE_EQ(s.throw_.spin.magnitude.mean, 30.0);
  EXPECT_DOUBLE_EQ(s.throw_.spin.magnitude.sd, 5.0);
  EXPECT_EQ(s.floor.restitution, 0.25);
  EXPECT_EQ(s.sim.max_bounces, 7);

  const SceneDef fixed = parse_scene(kMinimal + "[throw.spin]\nkind = \"fixed\"\nmean = [0, 0, 40]\n", "x");
  EXPECT_EQ(fixed.throw_.spin.kind, SpinKind::Normal);
  EXPECT_EQ(fixed.throw_.spin.components.mean, Vec3(0, 0, 40));
  EXPECT_EQ(fixed.throw_.spin.components.sd, Vec3::Zero());

  const SceneDef octant = parse_scene(kMinimal + "[throw.spin]\nkind = \"octant-axis\"\nmean = 20\n", "x");
  EXPECT_EQ(octant.throw_.spin.kind, SpinKind::OctantAxis);
  EXPECT_DOUBLE_EQ(octant.throw_.spin.magnitude.mean, 20.0);
}

// ---- --set overrides ----------------------------------------------------------------------------

TEST(SceneOverride, EveryDocumentedKeyWorksOnDie1) {
  const SceneDef s = load_scene(kDie1, {
                                           "materials.steel.density=7930",
                                           "materials.steel.restitution=0.6",
                                           "materials.aluminium.restitution = 0.45",
                                           "throw.spin.sd=[5, 6, 7]",
                                           "throw.height.mean=0.8",
                                           "sim.fidelity=paper",
                                           "sim.stop_speed=0.001",
                                       });
  EXPECT_DOUBLE_EQ(s.materials.at("steel").density, 7930.0);
  EXPECT_DOUBLE_EQ(s.materials.at("steel").restitution, 0.6);
  EXPECT_DOUBLE_EQ(s.materials.at("aluminium").restitution, 0.45);
  EXPECT_EQ(s.throw_.spin.components.sd, Vec3(5, 6, 7));
  EXPECT_DOUBLE_EQ(s.throw_.height.mean, 0.8);
  EXPECT_DOUBLE_EQ(s.throw_.height.sd, 0.2);  // untouched sibling keeps its default
  EXPECT_EQ(s.sim.fidelity, Fidelity::Paper);
  EXPECT_DOUBLE_EQ(s.sim.stop_speed, 0.001);

  EXPECT_EQ(load_scene(kDie1, {"throw.spin.sd=4"}).throw_.spin.components.sd, Vec3::Constant(4.0));
  EXPECT_EQ(load_scene(kDie1, {"sim.fidelity=\"paper\""}).sim.fidelity, Fidelity::Paper);
  EXPECT_EQ(load_scene(kDie1, {"die.faces.+z=9"}).die.face_labels[4], 9);
}

TEST(SceneOverride, LaterOverrideWins) {
  EXPECT_DOUBLE_EQ(load_scene(kDie1, {"sim.stop_speed=1", "sim.stop_speed=2"}).sim.stop_speed, 2.0);
}

TEST(SceneExtends, ChainAndPrecedence) {
  TempDir dir;
  dir.write("base.toml", kMinimal + "[sim]\nstop_speed = 0.5\ngravity = 5.0\n[throw.height]\nmean = 2.0\n");
  dir.write("sub/mid.toml", "name = \"mid\"\nextends = \"../base.toml\"\n[sim]\nstop_speed = 0.25\n");
  const std::string top = dir.write("sub/top.toml", "extends = \"mid.toml\"\n[throw.height]\nsd = 0.0\n");

  const SceneDef s = load_scene(top);
  EXPECT_EQ(s.name, "top");  // the base's name is not inherited
  EXPECT_DOUBLE_EQ(s.sim.gravity, 5.0);         // base
  EXPECT_DOUBLE_EQ(s.sim.stop_speed, 0.25);     // mid over base
  EXPECT_DOUBLE_EQ(s.throw_.height.mean, 2.0);  // base, table merged with top's
  EXPECT_DOUBLE_EQ(s.throw_.height.sd, 0.0);    // top
  EXPECT_DOUBLE_EQ(s.materials.at("wood").density, 700.0);

  // --set beats every file of the chain.
  const SceneDef o = load_scene(top, {"sim.stop_speed=0.125", "sim.gravity=3"});
  EXPECT_DOUBLE_EQ(o.sim.stop_speed, 0.125);
  EXPECT_DOUBLE_EQ(o.sim.gravity, 3.0);
}

TEST(SceneExtends, ArraysReplace) {
  TempDir dir;
  dir.write("base.toml", kMinimal + "[materials.lead]\n[[die.regions]]\nmaterial = \"lead\"\n"
                                    "cuts = [{normal = [1, 0, 0]}, {normal = [0, 1, 0]}]\n");
  const std::string top = dir.write("top.toml", "extends = \"base.toml\"\n[[die.regions]]\nmaterial = \"wood\"\n");
  const SceneDef s = load_scene(top);
  ASSERT_EQ(s.die.regions.size(), 1u);
  EXPECT_EQ(s.die.regions[0].material, "wood");
  EXPECT_TRUE(s.die.regions[0].half_spaces.empty());
}

TEST(SceneExtends, FromMemoryIsRelativeToCurrentDirectory) {
  struct Cwd {  // restored even if parse_scene throws
    fs::path old = fs::current_path();
    ~Cwd() { fs::current_path(old); }
  } cwd;
  fs::current_path(DICESIM_SOURCE_DIR);
  const SceneDef s = parse_scene("extends = \"scenes/paper/die2.toml\"\n[sim]\nstop_speed = 0.2\n", "cli");
  EXPECT_EQ(s.name, "cli");
  EXPECT_DOUBLE_EQ(s.die.regions.at(0).half_spaces.at(0).offset, 0.009);
  EXPECT_DOUBLE_EQ(s.sim.stop_speed, 0.2);
}

TEST(SceneExtends, CycleIsAnError) {
  TempDir dir;
  const std::string a = dir.write("a.toml", "extends = \"b.toml\"\n");
  dir.write("b.toml", "extends = \"c.toml\"\n");
  dir.write("c.toml", "extends = \"a.toml\"\n");
  const SceneError e = error_of([&] { load_scene(a); });
  EXPECT_EQ(e.key(), "extends");
  expect_contains(e.what(), "cycle");
  expect_contains(e.what(), "c.toml");
  expect_contains(e.what(), "a.toml");

  const std::string self = dir.write("self.toml", "extends = \"self.toml\"\n");
  expect_contains(error_of([&] { load_scene(self); }).what(), "cycle");
}

TEST(SceneExtends, MissingBaseNamesTheExtendingFile) {
  TempDir dir;
  const std::string top = dir.write("top.toml", "extends = \"nowhere.toml\"\n");
  const SceneError e = error_of([&] { load_scene(top); });
  EXPECT_EQ(e.file(), top);
  EXPECT_EQ(e.key(), "extends");
  EXPECT_EQ(e.value(), "\"nowhere.toml\"");
  expect_contains(e.allowed(), "cannot open scene file");
}

TEST(SceneExtends, ErrorInBaseNamesTheBaseFile) {
  TempDir dir;
  const std::string base = dir.write("base.toml", kMinimal + "[sim]\ngravity = -1\n");
  const std::string top = dir.write("top.toml", "extends = \"base.toml\"\n");
  const SceneError e = error_of([&] { load_scene(top); });
  EXPECT_EQ(fs::path(e.file()).filename(), "base.toml");
  EXPECT_EQ(e.key(), "sim.gravity");
}

// ---- errors -------------------------------------------------------------------------------------

TEST(SceneErrors, MissingFile) {
  const SceneError e = error_of([] { load_scene("/nonexistent/dir/scene.toml"); });
  EXPECT_EQ(e.file(), "/nonexistent/dir/scene.toml");
  EXPECT_EQ(e.key(), "");
  EXPECT_EQ(e.allowed(), "cannot open scene file");
}

TEST(SceneErrors, SyntaxErrorHasLineAndColumn) {
  const SceneError e = parse_error("[die]\nmaterial = \"wood\"\nsize = [0.03, \n\n[sim\n");
  EXPECT_EQ(e.file(), "mem.toml");
  expect_contains(e.allowed(), "line ");
  expect_contains(e.allowed(), "column ");

  TempDir dir;
  const std::string path = dir.write("bad.toml", "a = \n");
  const SceneError f = error_of([&] { load_scene(path); });
  EXPECT_EQ(f.file(), path);
  expect_contains(f.allowed(), "line 1");
}

TEST(SceneErrors, UnknownKeyTopLevel) {
  const SceneError e = parse_error("colour = \"red\"\n" + kMinimal);
  EXPECT_EQ(e.file(), "mem.toml");
  EXPECT_EQ(e.key(), "colour");
  EXPECT_EQ(e.value(), "\"red\"");
  expect_contains(e.allowed(), "unknown key 'colour' at the top level");
  expect_contains(e.allowed(), "allowed: name, extends, materials, die, throw, floor, sim");
}

TEST(SceneErrors, UnknownKeyNested) {
  const SceneError e = error_of([] { parse_scene(R"(
[materials.steel]
densty = 7848.0
[die]
material = "steel"
)", "scenes/x.toml"); });
  EXPECT_EQ(std::string(e.what()),
            "scenes/x.toml: materials.steel.densty = 7848.0: unknown key 'densty' in [materials.steel]; "
            "allowed: density, restitution, friction, rolling_resistance, pivoting_resistance");

  const SceneError spin = parse_error(kMinimal + "[throw.spin]\nsdd = 3\n");
  EXPECT_EQ(spin.key(), "throw.spin.sdd");
  expect_contains(spin.allowed(), "in [throw.spin]; allowed: kind, mean, sd");

  const SceneError region = parse_error(kMinimal + "[[die.regions]]\nmaterial = \"wood\"\ncuts = [{normal = [1, 0, 0], ofset = 1}]\n");
  EXPECT_EQ(region.key(), "die.regions[0].cuts[0].ofset");
  expect_contains(region.allowed(), "allowed: normal, offset");

  const SceneError face = parse_error(kMinimal + "[die.faces]\n\"+w\" = 3\n");
  EXPECT_EQ(face.key(), "die.faces.\"+w\"");
  expect_contains(face.allowed(), "allowed: \"+x\", \"-x\", \"+y\", \"-y\", \"+z\", \"-z\"");
}

TEST(SceneErrors, WrongType) {
  const SceneError density = parse_error(kMinimal + "[materials.steel]\ndensity = \"heavy\"\n");
  EXPECT_EQ(density.key(), "materials.steel.density");
  EXPECT_EQ(density.value(), "\"heavy\"");
  expect_contains(density.allowed(), "must be a number");

  const SceneError material = parse_error("[materials.a]\n[die]\nmaterial = 3\n");
  EXPECT_EQ(material.key(), "die.material");
  EXPECT_EQ(material.allowed(), "must be a string");

  const SceneError size = parse_error(kMinimal + "size = [0.03, 0.03]\n");
  EXPECT_EQ(size.key(), "die.size");
  EXPECT_EQ(size.value(), "[0.03, 0.03]");
  expect_contains(size.allowed(), "must be a number or an array of 3 numbers");

  const SceneError normal = parse_error(kMinimal + "[[die.regions]]\nmaterial = \"wood\"\n"
                                                   "cuts = [{normal = [0, 0, 1]}, {normal = 1}]\n");
  EXPECT_EQ(normal.key(), "die.regions[0].cuts[1].normal");
  expect_contains(normal.allowed(), "must be an array of 3 numbers");

  const SceneError zero = parse_error(kMinimal + "[[die.regions]]\nmaterial = \"wood\"\ncuts = [{normal = [0, 0, 0]}]\n");
  EXPECT_EQ(zero.key(), "die.regions[0].cuts[0].normal");
  expect_contains(zero.allowed(), "not all 0");

  const SceneError table = parse_error("sim = 3\n" + kMinimal);
  EXPECT_EQ(table.key(), "sim");
  EXPECT_EQ(table.allowed(), "must be a table");

  const SceneError bounces = parse_error(kMinimal + "[sim]\nmax_bounces = 10.5\n");
  EXPECT_EQ(bounces.key(), "sim.max_bounces");
  expect_contains(bounces.allowed(), "must be an integer in [1, 10000000]");

  const SceneError boolean = parse_error(kMinimal + "[sim]\ngravity = true\n");
  expect_contains(boolean.allowed(), "must be a number");
}

TEST(SceneErrors, NegativeDensity) {
  const SceneError e = error_of([] { parse_scene(R"(
[materials.steel]
density = -5
[die]
material = "steel"
)", "scenes/paper/die1.toml"); });
  EXPECT_EQ(std::string(e.what()), "scenes/paper/die1.toml: materials.steel.density = -5: must be a number in (0, 1e6] kg/m^3");
  EXPECT_EQ(e.file(), "scenes/paper/die1.toml");
  EXPECT_EQ(e.key(), "materials.steel.density");
  EXPECT_EQ(e.value(), "-5");
}

TEST(SceneErrors, RestitutionOutOfRange) {
  for (const char* bad : {"1.5", "-0.1"}) {
    const SceneError e = error_of([&] { load_scene(kDie1, {std::string("materials.aluminium.restitution=") + bad}); });
    EXPECT_EQ(e.file(), std::string(kDie1) + " (--set)");
    EXPECT_EQ(e.key(), "materials.aluminium.restitution");
    EXPECT_EQ(e.value(), bad);
    EXPECT_EQ(e.allowed(), "must be a number in [0, 1]");
  }
  const SceneError floor = parse_error(kMinimal + "[floor]\nrestitution = 1.5\n");
  EXPECT_EQ(floor.key(), "floor.restitution");
  EXPECT_EQ(floor.value(), "1.5");
}

TEST(SceneErrors, ContactResistancesOutOfRange) {
  for (const char* key : {"rolling_resistance", "pivoting_resistance"}) {
    for (const char* bad : {"-0.001", "0.2"}) {
      const SceneError e = parse_error(kMinimal, {std::string("materials.wood.") + key + "=" + bad});
      EXPECT_EQ(e.key(), std::string("materials.wood.") + key);
      EXPECT_EQ(e.value(), bad);
      EXPECT_EQ(e.allowed(), "must be a number in [0, 0.1] m");
    }
  }
  EXPECT_EQ(parse_scene(kMinimal, "mem.toml").materials.at("wood").pivoting_resistance, 3e-6);  // the default
}

TEST(SceneErrors, NanAndInfinity) {
  const SceneError in_file = parse_error(kMinimal + "[throw.height]\nmean = nan\n");
  EXPECT_EQ(in_file.file(), "mem.toml");
  EXPECT_EQ(in_file.key(), "throw.height.mean");
  EXPECT_EQ(in_file.value(), "nan");
  expect_contains(in_file.allowed(), "must be finite");

  const SceneError via_set = error_of([] { load_scene(kDie1, {"materials.steel.density=nan"}); });
  EXPECT_EQ(via_set.file(), std::string(kDie1) + " (--set)");
  EXPECT_EQ(via_set.key(), "materials.steel.density");
  EXPECT_EQ(via_set.value(), "nan");
  expect_contains(via_set.allowed(), "must be finite");

  const SceneError inf = error_of([] { load_scene(kDie1, {"throw.spin.sd=[1, inf, 1]"}); });
  EXPECT_EQ(inf.key(), "throw.spin.sd[1]");
  expect_contains(inf.allowed(), "must be finite");
}

TEST(SceneErrors, UnknownOrMissingMaterial) {
  const SceneError region = parse_error(kMinimal + "[[die.regions]]\nmaterial = \"gold\"\n");
  EXPECT_EQ(region.key(), "die.regions[0].material");
  EXPECT_EQ(region.value(), "\"gold\"");
  expect_contains(region.allowed(), "must name a material in [materials]; defined: wood");

  const SceneError base = parse_error("[materials.wood]\n[die]\nmaterial = \"oak\"\n");
  EXPECT_EQ(base.key(), "die.material");
  expect_contains(base.allowed(), "defined: wood");

  const SceneError missing = parse_error("[materials.wood]\n");
  EXPECT_EQ(missing.file(), "mem.toml");
  EXPECT_EQ(missing.key(), "die.material");
  expect_contains(missing.allowed(), "required");

  const SceneError name = parse_error(kMinimal + "[materials.\"st eel\"]\n");
  expect_contains(name.allowed(), "[A-Za-z0-9_-]+");

  EXPECT_NO_THROW(parse_scene(kMinimal + "[materials.unused]\n", "x"));  // unused material is fine
}

TEST(SceneErrors, UnknownFidelityAndKinds) {
  const SceneError f = error_of([] { load_scene(kDie1, {"sim.fidelity=exact"}); });
  EXPECT_EQ(f.file(), std::string(kDie1) + " (--set)");
  EXPECT_EQ(f.key(), "sim.fidelity");
  EXPECT_EQ(f.value(), "\"exact\"");
  expect_contains(f.allowed(), kFidelityChoices);

  const SceneError spin = parse_error(kMinimal + "[throw.spin]\nkind = \"wild\"\n");
  EXPECT_EQ(spin.key(), "throw.spin.kind");
  EXPECT_EQ(spin.allowed(), "must be one of: \"normal\", \"random-axis\", \"octant-axis\", \"body-axis\", \"fixed\"");

  const SceneError axis = parse_error(kMinimal + "[throw.spin]\nkind = \"random-axis\"\nmean = [1, 2, 3]\n");
  EXPECT_EQ(axis.key(), "throw.spin.mean");
  expect_contains(axis.allowed(), "must be a number");

  const SceneError sd = parse_error(kMinimal + "[throw.velocity]\nsd = -1\n");
  EXPECT_EQ(sd.key(), "throw.velocity.sd");
  expect_contains(sd.allowed(), ">= 0 m/s");
}

TEST(SceneErrors, BadFaceLabels) {
  const SceneError range = parse_error(kMinimal + "[die.faces]\n\"+z\" = 0\n");
  EXPECT_EQ(range.key(), "die.faces.\"+z\"");
  EXPECT_EQ(range.value(), "0");
  expect_contains(range.allowed(), "integer in [1, 99]");

  const SceneError big = parse_error(kMinimal + "[die.faces]\n\"-x\" = 100\n");
  expect_contains(big.allowed(), "integer in [1, 99]");

  // +z = 2 collides with the default +x = 2: the stated key is the one blamed.
  const SceneError dup = parse_error(kMinimal + "[die.faces]\n\"+z\" = 2\n");
  EXPECT_EQ(dup.key(), "die.faces.\"+z\"");
  EXPECT_EQ(dup.value(), "2");
  expect_contains(dup.allowed(), "distinct");
  expect_contains(dup.allowed(), "+x and +z are both 2");
}

TEST(SceneErrors, OutOfRangeSimAndSize) {
  EXPECT_EQ(parse_error(kMinimal + "[sim]\ngravity = 0\n").allowed(), "must be a number in (0, 1000] m/s^2");
  EXPECT_EQ(parse_error(kMinimal + "[sim]\nmax_time = 0\n").allowed(), "must be a number in (0, 1e6] s");
  EXPECT_EQ(parse_error(kMinimal + "[sim]\nmax_bounces = 0\n").key(), "sim.max_bounces");
  const SceneError size = parse_error(kMinimal + "size = [0.03, -0.03, 0.03]\n");
  EXPECT_EQ(size.key(), "die.size[1]");
  EXPECT_EQ(size.value(), "-0.03");
  EXPECT_EQ(size.allowed(), "must be a number in (0, 100] m");
}

TEST(SceneErrors, MalformedOrUnknownOverride) {
  const SceneError no_eq = error_of([] { load_scene(kDie1, {"sim.stop_speed"}); });
  EXPECT_EQ(no_eq.file(), std::string(kDie1) + " (--set)");
  expect_contains(no_eq.allowed(), "KEY=VALUE");

  const SceneError empty_key = error_of([] { load_scene(kDie1, {"sim..stop_speed=1"}); });
  EXPECT_EQ(empty_key.file(), std::string(kDie1) + " (--set)");
  expect_contains(empty_key.allowed(), "malformed");

  const SceneError unknown = error_of([] { load_scene(kDie1, {"materials.steel.densty=1"}); });
  EXPECT_EQ(unknown.file(), std::string(kDie1) + " (--set)");
  EXPECT_EQ(unknown.key(), "materials.steel.densty");
  expect_contains(unknown.allowed(), "unknown key 'densty'");

  const SceneError new_table = error_of([] { load_scene(kDie1, {"thrown.height.mean=1"}); });
  EXPECT_EQ(new_table.file(), std::string(kDie1) + " (--set)");
  EXPECT_EQ(new_table.key(), "thrown");

  const SceneError ext = error_of([] { load_scene(kDie1, {"extends=x.toml"}); });
  EXPECT_EQ(ext.file(), std::string(kDie1) + " (--set)");
}

}  // namespace
}  // namespace dicesim

// ---- Shapes -----------------------------------------------------------------------------------
namespace dicesim {
namespace {

SceneError shape_error(const std::string& die_keys) {
  return error_of([&] { parse_scene(kMinimal + die_keys, "shape.toml"); });
}

TEST(SceneShapes, EveryShapeKeyIsReadWithItsDefaults) {
  const SceneDef box = parse_scene(kMinimal, "s");
  EXPECT_EQ(box.die.shape, ShapeKind::Box);
  EXPECT_EQ(box.die.rounding, 0.0);
  EXPECT_FALSE(box.die.read_down.has_value());
  const SceneDef d20 = parse_scene(kMinimal + "shape = \"d20\"\nsize = 0.02\nrounding = 0.001\nread = \"down\"\n"
                                                "[[die.labels]]\nnormal = [0, 0, 1]\nlabel = 20\n", "s");
  EXPECT_EQ(d20.die.shape, ShapeKind::D20);
  EXPECT_EQ(d20.die.size, Vec3::Constant(0.02));
  EXPECT_EQ(d20.die.rounding, 0.001);
  EXPECT_EQ(d20.die.read_down, std::optional<bool>(true));
  ASSERT_EQ(d20.die.labels.size(), 1u);
  EXPECT_EQ(d20.die.labels[0].label, 20);
  const SceneDef prism = parse_scene(kMinimal + "shape = \"prism\"\nsides = 5\nradius = 0.008\nlength = 0.04\n", "s");
  EXPECT_EQ(prism.die.sides, 5);
  EXPECT_EQ(prism.die.radius, 0.008);
  EXPECT_EQ(prism.die.length, 0.04);
  const SceneDef hull = parse_scene(kMinimal + "shape = \"hull\"\nscale = 0.001\nvertices = [[0,0,0],[1,0,0],[0,1,0],[0,0,1]]\n", "s");
  EXPECT_EQ(hull.die.vertices.size(), 4u);
  EXPECT_EQ(hull.die.scale, 0.001);
}

TEST(SceneShapes, MeshTextIsReadRelativeToTheSceneFile) {
  TempDir dir;
  dir.write("meshes/cube.obj", "v 0 0 0\n");
  const std::string scene = dir.write("dice/cube.toml", kMinimal + "shape = \"mesh\"\nmesh = \"../meshes/cube.obj\"\n");
  const SceneDef s = load_scene(scene);
  EXPECT_EQ(s.die.mesh, "../meshes/cube.obj");
  EXPECT_EQ(s.die.mesh_text, "v 0 0 0\n");
  EXPECT_NE(s.die.mesh_path.find("meshes/cube.obj"), std::string::npos);
  // A scene that extends it finds the mesh relative to the file the key is written in.
  const std::string derived = dir.write("other/derived.toml", "extends = \"../dice/cube.toml\"\n");
  EXPECT_EQ(load_scene(derived).die.mesh_text, "v 0 0 0\n");

  const SceneError missing = error_of([&] { load_scene(dir.write("dice/bad.toml", kMinimal + "shape = \"mesh\"\nmesh = \"nope.obj\"\n")); });
  EXPECT_EQ(missing.key(), "die.mesh");
  EXPECT_EQ(missing.value(), "\"nope.obj\"");
  expect_contains(missing.allowed(), "cannot open mesh file");
  expect_contains(missing.allowed(), "nope.obj");
}

TEST(SceneShapes, BadShapeKeysNameKeyValueAndRange) {
  const SceneError shape = shape_error("shape = \"d7\"\n");
  EXPECT_EQ(shape.key(), "die.shape");
  EXPECT_EQ(shape.value(), "\"d7\"");
  expect_contains(shape.allowed(), "\"d4\", \"d6\"");
  expect_contains(shape.allowed(), "\"mesh\"");

  const SceneError read = shape_error("read = \"sideways\"\n");
  EXPECT_EQ(read.key(), "die.read");
  expect_contains(read.allowed(), "\"up\", \"down\"");

  const SceneError sides = shape_error("shape = \"prism\"\nsides = 2\n");
  EXPECT_EQ(sides.key(), "die.sides");
  EXPECT_EQ(sides.value(), "2");
  expect_contains(sides.allowed(), "integer in [3, 1000]");

  const SceneError not_for = shape_error("shape = \"d20\"\nsides = 5\n");
  EXPECT_EQ(not_for.key(), "die.sides");
  expect_contains(not_for.allowed(), "does not apply to shape = \"d20\"");

  const SceneError preset_size = shape_error("shape = \"d8\"\nsize = [0.02, 0.02, 0.02]\n");
  EXPECT_EQ(preset_size.key(), "die.size");
  expect_contains(preset_size.allowed(), "distance between opposite faces");

  const SceneError few = shape_error("shape = \"hull\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\n");
  EXPECT_EQ(few.key(), "die.vertices");
  expect_contains(few.allowed(), "at least 4 points");

  const SceneError missing = shape_error("shape = \"hull\"\n");
  EXPECT_EQ(missing.key(), "die.vertices");
  expect_contains(missing.allowed(), "required");

  const SceneError rounding = shape_error("rounding = -0.001\n");
  EXPECT_EQ(rounding.key(), "die.rounding");
  expect_contains(rounding.allowed(), "[0, 100) m");

  const SceneError label = shape_error("[[die.labels]]\nnormal = [0, 0, 0]\nlabel = 1\n");
  EXPECT_EQ(label.key(), "die.labels[0].normal");

  const SceneError mesh_rounding = shape_error("shape = \"mesh\"\nmesh = \"x.obj\"\nrounding = 0.001\n");
  EXPECT_EQ(mesh_rounding.key(), "die.rounding");
  expect_contains(mesh_rounding.allowed(), "does not apply to shape = \"mesh\"");

  const SceneError faces = shape_error("shape = \"d8\"\n[die.faces]\n\"+z\" = 1\n");
  EXPECT_EQ(faces.key(), "die.faces");
  expect_contains(faces.allowed(), "[[die.labels]]");
}

}  // namespace
}  // namespace dicesim

// ---- [floor] friction and indexed --set keys (what `dicesim fit` varies) ---------------------------
namespace dicesim {
namespace {

// Every contact of every kind of body takes the floor's friction: corners of a sharp polyhedron,
// of a rounded one, and a coin's rim features. max_friction follows (the stepper and rest use it).
TEST(SceneFloor, FrictionOverridesEveryContact) {
  for (const char* scene : {"paper/die1.toml", "dice/d6.toml", "coins/quarter-table.toml"}) {
    SCOPED_TRACE(scene);
    const SceneDef plain = load_scene(kScenes + scene);
    EXPECT_FALSE(plain.floor.friction.has_value());
    const DieModel before = compile(plain);
    ASSERT_FALSE(before.vertex_friction.empty());
    EXPECT_NE(before.vertex_friction.front(), 0.7);  // the materials' 0.3: the override must show

    const SceneDef set = load_scene(kScenes + scene, {"floor.friction=0.7"});
    EXPECT_EQ(set.floor.friction, 0.7);
    const DieModel m = compile(set);
    ASSERT_EQ(m.vertex_friction.size(), before.vertex_friction.size());
    for (double mu : m.vertex_friction) EXPECT_EQ(mu, 0.7);
    EXPECT_EQ(m.max_friction, 0.7);
    EXPECT_EQ(m.vertex_restitution, before.vertex_restitution);  // friction only
  }
  EXPECT_EQ(parse_scene(kMinimal + "[floor]\nfriction = 0\n", "x").floor.friction, 0.0);
}

TEST(SceneFloor, FrictionChangesImpulseResults) {
  RunConfig cfg;
  cfg.seed = 3;
  cfg.tosses = 300;
  auto counts = [&](const std::string& mu) {
    return run_tosses(compile(load_scene(kDie1, {"sim.fidelity=impulse", "floor.friction=" + mu})), cfg).faces;
  };
  EXPECT_NE(counts("0.05"), counts("0.9"));
}

TEST(SceneErrors, FloorFrictionOutOfRange) {
  for (const char* bad : {"10.5", "-0.1"}) {
    const SceneError e = error_of([&] { load_scene(kDie1, {std::string("floor.friction=") + bad}); });
    EXPECT_EQ(e.file(), std::string(kDie1) + " (--set)");
    EXPECT_EQ(e.key(), "floor.friction");
    EXPECT_EQ(e.value(), bad);
    EXPECT_EQ(e.allowed(), "must be a number in [0, 10]");
  }
  const SceneError in_file = parse_error(kMinimal + "[floor]\nfriction = \"high\"\n");
  EXPECT_EQ(in_file.file(), "mem.toml");
  EXPECT_EQ(in_file.key(), "floor.friction");
  EXPECT_EQ(in_file.allowed(), "must be a number in [0, 10]");
}

// Die 1's steel slab is z >= 0 ((0, 0, -1) . x <= offset); offset 5 mm moves its face down to
// z = -5 mm: 20 mm of steel over 10 mm of aluminium, so the COM drops from 3.65 mm to 2.79 mm.
TEST(SceneOverride, IndexedKeyMovesARegionsCut) {
  const SceneDef s = load_scene(kDie1, {"die.regions[0].cuts[0].offset=0.005"});
  ASSERT_EQ(s.die.regions.size(), 1u);
  ASSERT_EQ(s.die.regions[0].half_spaces.size(), 1u);
  EXPECT_DOUBLE_EQ(s.die.regions[0].half_spaces[0].offset, 0.005);
  EXPECT_EQ(s.die.regions[0].half_spaces[0].normal, Vec3(0, 0, -1));  // its sibling is kept
  EXPECT_EQ(s.die.regions[0].material, "steel");

  const double steel = 7848.0, alu = 2714.3, a = 0.03;
  const MassProperties before = compile(load_scene(kDie1)).mass_geometric;
  const MassProperties after = compile(s).mass_geometric;
  EXPECT_NEAR(before.com.z(), (steel - alu) * 0.0075 / (steel + alu), 1e-12);
  EXPECT_NEAR(after.com.z(), (steel * 0.02 * 0.005 - alu * 0.01 * 0.01) / (steel * 0.02 + alu * 0.01), 1e-12);
  EXPECT_LT(after.com.z(), before.com.z());
  EXPECT_NEAR(after.mass, a * a * (steel * 0.02 + alu * 0.01), 1e-12);

  // The key may end in an index: that element is replaced (here the cut's normal flips to z <= 0).
  const SceneDef flipped = load_scene(kDie1, {"die.regions[0].cuts[0].normal[2]=1"});
  EXPECT_EQ(flipped.die.regions[0].half_spaces[0].normal, Vec3(0, 0, 1));
  EXPECT_NEAR(compile(flipped).mass_geometric.com.z(), -before.com.z(), 1e-12);
  // Later overrides still win, indexed or not.
  EXPECT_DOUBLE_EQ(load_scene(kDie1, {"die.regions[0].cuts[0].offset=0.001", "die.regions[0].cuts[0].offset=0.002"})
                       .die.regions[0].half_spaces[0].offset,
                   0.002);
}

// The walk is over the merged tree: an index reaches a region that a base scene defines.
TEST(SceneOverride, IndexedKeyReachesAnArrayFromTheBase) {
  TempDir dir;
  dir.write("base.toml", kMinimal + "[materials.lead]\ndensity = 11340.0\n[[die.regions]]\nmaterial = \"lead\"\n"
                                    "cuts = [{ normal = [1, 0, 0], offset = 0.0 }]\n");
  const std::string top = dir.write("top.toml", "extends = \"base.toml\"\n[throw.height]\nmean = 0.5\n");
  const SceneDef s = load_scene(top, {"die.regions[0].cuts[0].offset=-0.004", "die.regions[0].material=wood"});
  EXPECT_DOUBLE_EQ(s.die.regions[0].half_spaces[0].offset, -0.004);
  EXPECT_EQ(s.die.regions[0].material, "wood");
}

TEST(SceneErrors, IndexedOverride) {
  const std::string set = std::string(kDie1) + " (--set)";
  // Out of range: names the key, the index and the array's length.
  const SceneError range = error_of([] { load_scene(kDie1, {"die.regions[1].cuts[0].offset=0"}); });
  EXPECT_EQ(range.file(), set);
  EXPECT_EQ(range.key(), "die.regions[1].cuts[0].offset");
  EXPECT_EQ(range.allowed(), "index 1 is out of range: die.regions has 1 element (indices 0 to 0)");
  const SceneError inner = error_of([] { load_scene(kDie1, {"die.regions[0].cuts[0].normal[3]=1"}); });
  EXPECT_EQ(inner.allowed(), "index 3 is out of range: die.regions[0].cuts[0].normal has 3 elements (indices 0 to 2)");

  // An index into something that is not an array.
  const SceneError scalar = error_of([] { load_scene(kDie1, {"die.size[0]=0.02"}); });
  EXPECT_EQ(scalar.file(), set);
  EXPECT_EQ(scalar.key(), "die.size[0]");
  EXPECT_EQ(scalar.allowed(), "die.size is a number, not an array: it cannot take the index [0]");
  const SceneError table = error_of([] { load_scene(kDie1, {"die.faces[0]=1"}); });
  expect_contains(table.allowed(), "die.faces is a table, not an array");

  // The array must exist (die 1 states no [[die.labels]]), and a dotted key after an index needs a table.
  const SceneError absent = error_of([] { load_scene(kDie1, {"die.labels[0].label=3"}); });
  EXPECT_EQ(absent.key(), "die.labels[0].label");
  expect_contains(absent.allowed(), "die.labels is not in the scene");
  const SceneError into_number = error_of([] { load_scene(kDie1, {"die.regions[0].cuts[0].normal[0].x=1"}); });
  EXPECT_EQ(into_number.allowed(), "die.regions[0].cuts[0].normal[0] is a number, not a table: it has no key 'x'");

  // Malformed indices.
  for (const char* bad : {"die.regions[-1].material=steel", "die.regions[x].material=steel", "die.regions[0.material=steel",
                          "die.regions[0]x.material=steel", "die.[0].material=steel"}) {
    const SceneError e = error_of([&] { load_scene(kDie1, {bad}); });
    EXPECT_EQ(e.file(), set) << bad;
    expect_contains(e.allowed(), "malformed override");
  }
  EXPECT_EQ(error_of([] { load_scene(kDie1, {"extends[0]=x.toml"}); }).file(), set);

  // Values set by index are checked later like any other and carry the (--set) name; so do the
  // tables a dotted key after an index creates.
  const SceneError value = error_of([] { load_scene(kDie1, {"die.regions[0].cuts[0].offset=far"}); });
  EXPECT_EQ(value.file(), set);
  EXPECT_EQ(value.key(), "die.regions[0].cuts[0].offset");
  EXPECT_EQ(value.value(), "\"far\"");
  const SceneError element = error_of([] { load_scene(kDie1, {"die.regions[0].cuts[0].normal[1]=true"}); });
  EXPECT_EQ(element.file(), set);
  EXPECT_EQ(element.key(), "die.regions[0].cuts[0].normal[1]");
  const SceneError created = error_of([] { load_scene(kDie1, {"die.regions[0].cuts[0].extra.depth=1"}); });
  EXPECT_EQ(created.file(), set);
  EXPECT_EQ(created.key(), "die.regions[0].cuts[0].extra");
  expect_contains(created.allowed(), "unknown key 'extra'");
}

}  // namespace
}  // namespace dicesim

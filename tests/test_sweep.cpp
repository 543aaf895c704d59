// Sweeps: SPEC parsing, overrides per point, common random numbers, the paper's sweep files.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "scenes_for_tests.hpp"
#include "temp_files.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/initial_state.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/sweep.hpp"

namespace dicesim {
namespace {

namespace fs = std::filesystem;
const std::string kSrc = DICESIM_SOURCE_DIR;
const std::string kDie1 = kSrc + "/scenes/paper/die1.toml";

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = dicesim::testing::unique_temp(name);
  std::ofstream(path) << text;
  return path;
}

TEST(SweepValues, RangeIncludesStopExactly) {
  const auto v = parse_values("0.4:4.2:0.2");
  ASSERT_EQ(v.size(), 20u);
  EXPECT_DOUBLE_EQ(v.front(), 0.4);
  EXPECT_EQ(v.back(), 4.2);  // snapped to stop, not 4.200000000000001
  const auto f = parse_values("1/30:30/30:1/30");
  ASSERT_EQ(f.size(), 30u);
  EXPECT_EQ(f.front(), 1.0 / 30.0);
  EXPECT_EQ(f.back(), 1.0);
  EXPECT_NEAR(f[18], 19.0 / 30.0, 1e-15);
  EXPECT_EQ(parse_values("0.04:0.96:0.04")[20], 0.84);  // not 0.8400000000000001
}

TEST(SweepValues, ListsAndDescendingRanges) {
  EXPECT_EQ(parse_values("0.1, 0.5,0.9"), (std::vector<double>{0.1, 0.5, 0.9}));
  EXPECT_EQ(parse_values("3:1:-1"), (std::vector<double>{3, 2, 1}));
  EXPECT_EQ(parse_values("7"), (std::vector<double>{7}));
  EXPECT_EQ(parse_values("1/4,-2"), (std::vector<double>{0.25, -2}));
}

TEST(SweepValues, BadSpecsNameTheOptionAndValue) {
  for (const char* bad : {"1:2:0", "1:2", "2:1:1", "a,b", "", "1:2:3:4", "1/0", "nan", "1,,2", "0:1e9:1e-3"}) {
    try {
      parse_values(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const SceneError& e) {
      EXPECT_EQ(e.key(), "--values") << bad;
      EXPECT_NE(std::string(e.what()).find(std::string("'") + bad + "'"), std::string::npos) << e.what();
    }
  }
}

TEST(SweepParam, TemplateScaleAndShift) {
  SweepParam p;
  p.key = "throw.velocity.mean";
  p.value_template = "[{}, 0, 0]";
  EXPECT_EQ(p.override_for(2.5), "throw.velocity.mean=[2.5, 0, 0]");
  SweepParam q;
  q.key = "a.b";
  q.scale = 0.03;
  q.shift = -0.015;
  EXPECT_EQ(q.override_for(0.5), "a.b=0");
  EXPECT_EQ(q.override_for(1.0), "a.b=0.015");
}

// The contract: every point uses the same seed and toss indices, so a parameter that the
// `paper` model never reads (friction) gives identical counts at every value, and each point
// equals a plain run of the same scene.
TEST(SweepRun, CommonRandomNumbers) {
  SweepParam p;
  p.key = "materials.steel.friction";
  p.values = {0.1, 0.5, 2.0};
  SweepSpec spec = sweep_from_param(kDie1, p);
  spec.tosses = 1500;
  spec.seed = 42;
  SweepRunOptions opt;
  opt.threads = 2;
  const SweepResult r = run_sweep(spec, opt);
  ASSERT_EQ(r.points.size(), 3u);
  EXPECT_EQ(r.points[0].counts, r.points[1].counts);
  EXPECT_EQ(r.points[0].counts, r.points[2].counts);
  EXPECT_EQ(r.points[0].counts.total(), 1500u);

  RunConfig cfg;
  cfg.seed = 42;
  cfg.tosses = 1500;
  cfg.threads = 1;
  const DieModel m = compile(load_scene(kDie1, {"materials.steel.friction=0.5"}), kDie1);
  EXPECT_EQ(run_tosses(m, cfg), r.points[1].counts);
}

TEST(SweepRun, TheParameterMattersAndTheSeedIsUsed) {
  SweepParam p;
  p.key = "floor.restitution";
  p.values = {0.1, 0.9};
  SweepSpec spec = sweep_from_param(kDie1, p);
  spec.tosses = 1000;
  const SweepResult a = run_sweep(spec, {});
  EXPECT_NE(a.points[0].counts, a.points[1].counts);
  spec.seed = 2;
  const SweepResult b = run_sweep(spec, {});
  EXPECT_NE(a.points[0].counts, b.points[0].counts);
}

TEST(SweepRun, BadPointFailsBeforeAnyToss) {
  SweepParam p;
  p.key = "floor.restitution";
  p.values = {0.5, 1.5};
  SweepSpec spec = sweep_from_param(kDie1, p);
  spec.tosses = 1000000000;  // would take hours if tossing started
  try {
    run_sweep(spec, {});
    FAIL() << "restitution 1.5 accepted";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.key(), "floor.restitution");
    EXPECT_EQ(e.value(), "1.5");
  }
}

// The sec. 5.4 file builds, at k/30, the same die as a steel/aluminium slab cube with that
// aluminium fraction (mass and centre of mass), and a homogeneous cube at 30/30.
TEST(SweepFiles, VolumeRatioPointsAreSlabDice) {
  const SweepSpec s = load_sweep_file(kSrc + "/scenes/paper/sweeps/volume-ratio.toml");
  ASSERT_EQ(s.points.size(), 30u);
  for (int k : {1, 15, 19, 29, 30}) {
    const SweepPoint& pt = s.points[static_cast<std::size_t>(k - 1)];
    EXPECT_NEAR(pt.x, k / 30.0, 1e-12);
    std::vector<std::string> all = s.overrides;
    all.insert(all.end(), pt.overrides.begin(), pt.overrides.end());
    const DieModel m = compile(load_scene(s.scene, all), s.scene);
    const DieModel ref = compile(testing::slab_scene(k / 30.0), "ref");
    EXPECT_NEAR(m.mass, ref.mass, 1e-12 * ref.mass) << k;
    EXPECT_NEAR((m.mass_geometric.com - ref.mass_geometric.com).norm(), 0.0, 1e-12) << k;
    EXPECT_EQ(m.face_labels, ref.face_labels);
  }
  const SweepPoint& last = s.points.back();
  std::vector<std::string> all = s.overrides;
  all.insert(all.end(), last.overrides.begin(), last.overrides.end());
  const DieModel homog = compile(load_scene(s.scene, all), s.scene);
  EXPECT_NEAR(homog.mass, 2714.3 * 2.7e-5, 1e-12);
  EXPECT_LT(homog.mass_geometric.com.norm(), 1e-12);
}

// Every paper sweep file loads, every point compiles, and every point has the seed's row.
TEST(SweepFiles, EveryPaperSweepMatchesItsSeedTable) {
  int files = 0;
  for (const auto& e : fs::directory_iterator(kSrc + "/scenes/paper/sweeps")) {
    if (e.path().extension() != ".toml") continue;
    ++files;
    const std::string path = e.path().string();
    ASSERT_TRUE(is_sweep_file(path)) << path;
    const SweepSpec s = load_sweep_file(path);
    EXPECT_FALSE(s.reading.empty()) << path << ": say how the seed's settings were read";
    ASSERT_FALSE(s.seed_table.empty()) << path;
    EXPECT_GT(s.seed_tosses, 0u) << path;
    const auto rows = load_reference_table(s.seed_table);
    EXPECT_EQ(rows.size(), s.points.size()) << path;
    for (const SweepPoint& p : s.points) {
      EXPECT_TRUE(find_reference(rows, p.x).has_value()) << path << " x = " << p.x;
      std::vector<std::string> all = s.overrides;
      all.insert(all.end(), p.overrides.begin(), p.overrides.end());
      EXPECT_NO_THROW(compile(load_scene(s.scene, all), s.scene)) << path << " x = " << p.x;
    }
  }
  EXPECT_EQ(files, 6);
  EXPECT_FALSE(is_sweep_file(kDie1));
}

// Sec. 5.10: the point labelled k starts with face k on top.
TEST(SweepFiles, InitialOrientationPutsTheNamedFaceUp) {
  const SweepSpec s = load_sweep_file(kSrc + "/scenes/paper/sweeps/initial-orientation.toml");
  ASSERT_EQ(s.points.size(), 6u);
  for (const SweepPoint& p : s.points) {
    std::vector<std::string> all = s.overrides;
    all.insert(all.end(), p.overrides.begin(), p.overrides.end());
    const SceneDef def = load_scene(s.scene, all);
    const InitialState st = draw_initial_state(def.throw_, 1, 0);
    int best = -1;
    double best_z = -2.0;
    for (int f = 0; f < 6; ++f) {
      Vec3 n = Vec3::Zero();
      n[f / 2] = f % 2 == 0 ? 1.0 : -1.0;
      const double z = (st.orientation * n).z();
      if (z > best_z) {
        best_z = z;
        best = f;
      }
    }
    EXPECT_NEAR(best_z, 1.0, 1e-12);
    EXPECT_EQ(def.die.face_labels[static_cast<std::size_t>(best)], static_cast<int>(p.x)) << p.label;
  }
}

TEST(SweepFiles, ErrorsNameFileAndKey) {
  auto expect_error = [](const std::string& text, const std::string& key, const std::string& words) {
    const std::string path = write_temp("bad_sweep.toml", text);
    try {
      load_sweep_file(path);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const SceneError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.key(), key) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  const std::string scene = "scene = \"" + kDie1 + "\"\n";
  expect_error("[sweep]\n" + scene + "tosess = 5\n[sweep.param]\nkey = \"a\"\nvalues = \"1\"\n", "sweep.tosess", "unknown key");
  expect_error("[sweep]\nscene = \"nope.toml\"\n[sweep.param]\nkey = \"a\"\nvalues = \"1\"\n", "sweep.scene", "cannot open");
  expect_error("[sweep]\n" + scene, "sweep.param", "exactly one");
  expect_error("[sweep]\n" + scene + "[sweep.param]\nkey = \"a\"\nvalues = \"1:2:0\"\n", "sweep.param.values", "step");
  expect_error("[sweep]\n" + scene + "tosses = 0\n[sweep.param]\nkey = \"a\"\nvalues = \"1\"\n", "sweep.tosses", "integer");
  expect_error("[sweep]\n" + scene + "[sweep.param]\nkey = \"a\"\nvalues = \"1\"\ntemplate = \"[1, 2]\"\n",
               "sweep.param.template", "{}");
  expect_error("[sweep]\n" + scene + "[[sweep.points]]\nlabel = \"x\"\n", "sweep.points[0].x", "required");
}

TEST(SweepReference, SeedTableRows) {
  const auto rows = load_reference_table(kSrc + "/data/seed-tables/table08_volume_ratio.csv");
  ASSERT_EQ(rows.size(), 30u);
  const auto r = find_reference(rows, 19.0 / 30.0);
  ASSERT_TRUE(r.has_value());
  EXPECT_DOUBLE_EQ(r->p[0], 0.0802);
  EXPECT_DOUBLE_EQ(r->p[5], 0.2591);
  EXPECT_FALSE(find_reference(rows, 0.65).has_value());
}

}  // namespace
}  // namespace dicesim

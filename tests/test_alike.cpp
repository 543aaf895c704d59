// Which outcomes a report may test against each other (sim/body/symmetry.hpp: alike by the die's
// symmetry, shape and materials), and how a die resting with no single face up is read (the tie
// rule, sim/models/compile.cpp): the chi-square lines, `info`'s map, the refusal of an open tie.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <fstream>
#include <string>
#include <vector>

#include "cli_runner.hpp"
#include "sim/body/outcome.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/study/statistics.hpp"

namespace dicesim {
namespace {

using Groups = std::vector<std::vector<int>>;

std::string ready(const std::string& rel) { return std::string(DICESIM_SOURCE_DIR) + "/scenes/" + rel; }

DieModel model_of(const std::string& path, const std::vector<std::string>& overrides = {}) {
  return compile(load_scene(path, overrides), path);
}

// A 16 mm plastic cube labelled as a standard d6 with its (+,+,+) corner cut off through the
// midpoints of its three edges: 3-fold symmetric about (1,1,1). Lying on the cut, faces -x, -y and
// -z (5, 4, 6) are equally near up. `extra` is appended to the [die] table.
std::string chipped_scene(const std::string& extra = "") {
  const std::string path = testing::unique_temp("chipped.toml");
  std::ofstream(path) << "[materials.plastic]\ndensity = 1180.0\nrestitution = 0.5\nfriction = 0.3\n\n"
                         "[die]\nshape = \"hull\"\nscale = 0.001\nmaterial = \"plastic\"\n"
                         "vertices = [[-8, -8, -8], [8, -8, -8], [-8, 8, -8], [8, 8, -8], [-8, -8, 8], [8, -8, 8],\n"
                         "            [-8, 8, 8], [0, 8, 8], [8, 0, 8], [8, 8, 0]]\n"
                         "labels = [{ normal = [0, 0, 1], label = 1 }, { normal = [0, 0, -1], label = 6 },\n"
                         "          { normal = [1, 0, 0], label = 2 }, { normal = [-1, 0, 0], label = 5 },\n"
                         "          { normal = [0, 1, 0], label = 3 }, { normal = [0, -1, 0], label = 4 }"
                      << extra << "]\n";
  return path;
}

TEST(Alike, EveryOutcomeOfARegularDieIsAlike) {
  const std::vector<std::pair<std::string, int>> dice = {{"d4", 12}, {"d6", 24}, {"d8", 24}, {"d10", 10}, {"d12", 60}, {"d20", 60}};
  for (const auto& [name, rotations] : dice) {
    const DieModel m = model_of(ready("dice/" + name + ".toml"));
    EXPECT_EQ(m.symmetry_rotations, rotations) << name << ": " << m.alike_note;
    const Groups g = alike_groups(m);
    ASSERT_EQ(g.size(), 1u) << name;
    EXPECT_EQ(g[0], m.outcome_labels) << name;
  }
}

// The 3-sided prism: its sides are alike, its ends are alike, a side is not an end.
TEST(Alike, APrismsSidesAndEndsAreTwoGroups) {
  const DieModel m = model_of(ready("dice/prism3.toml"));
  EXPECT_EQ(m.symmetry_rotations, 6);
  EXPECT_EQ(alike_groups(m), (Groups{{1, 2, 3}, {4, 5}}));
}

// A load breaks the symmetries it does not share: Die 1's steel half keeps the four rotations
// about z (its sides 2-5 alike; 1 and 6 alone); the loaded d20's steel cap, cut parallel to a
// face, keeps the three about that face's normal (six groups of three; that face and its opposite
// alone); a fixed orientation leaves nothing alike.
TEST(Alike, ALoadOrAThrowKeepsOnlyTheSymmetriesItShares) {
  const DieModel die1 = model_of(ready("paper/die1.toml"));
  EXPECT_EQ(die1.symmetry_rotations, 4);
  EXPECT_EQ(alike_groups(die1), (Groups{{2, 3, 4, 5}}));
  const DieModel loaded = model_of(ready("dice/loaded-d20.toml"));
  EXPECT_EQ(loaded.symmetry_rotations, 3) << loaded.alike_note;
  const Groups g = alike_groups(loaded);
  ASSERT_EQ(g.size(), 6u);
  for (const auto& group : g) EXPECT_EQ(group.size(), 3u);
  const DieModel fixed = model_of(ready("dice/d6.toml"), {"throw.orientation.kind=\"fixed\""});
  EXPECT_TRUE(alike_groups(fixed).empty());
  EXPECT_NE(fixed.alike_note.find("throw.orientation"), std::string::npos) << fixed.alike_note;
  const DieModel quarter = model_of(ready("coins/quarter.toml"));
  EXPECT_EQ(alike_groups(quarter), (Groups{{1, 2}}));  // heads and tails; the edge alone
}

TEST(CliAlike, APrismIsTestedWithinItsGroupsNotAgainstAFairDie) {
  const std::string prism = ready("dice/prism3.toml");
  const testing::CliRun r = testing::run_dicesim("toss " + prism + " -n 3000 --fidelity static --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["chi2_uniform"].is_null()) << j["chi2_uniform"];
  ASSERT_EQ(j["chi2_alike"].size(), 2u);
  EXPECT_EQ(j["chi2_alike"][0]["outcomes"], nlohmann::json({1, 2, 3}));
  EXPECT_EQ(j["chi2_alike"][0]["dof"], 2);
  EXPECT_EQ(j["chi2_alike"][1]["outcomes"], nlohmann::json({4, 5}));
  EXPECT_EQ(j["alike"]["groups"], nlohmann::json({{1, 2, 3}, {4, 5}}));
  const testing::CliRun t = testing::run_dicesim("toss " + prism + " -n 3000 --fidelity static");
  EXPECT_EQ(t.out.find("a fair die"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("chi-square within the outcomes alike"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("  1, 2, 3 "), std::string::npos) << t.out;
  // A fair d6 is still tested against a fair die; a die thrown at a fixed orientation is not tested.
  const auto d6 = nlohmann::json::parse(testing::run_dicesim("toss " + ready("dice/d6.toml") + " -n 1000 --fidelity static --json").out);
  EXPECT_EQ(d6["chi2_uniform"]["dof"], 5);
  const testing::CliRun fixed = testing::run_dicesim("toss " + ready("dice/d6.toml") +
                                                     " -n 200 --fidelity static --set throw.orientation.kind='\"fixed\"'");
  EXPECT_NE(fixed.out.find("no chi-square test: no two outcomes are alike by design"), std::string::npos) << fixed.out;
  const testing::CliRun info = testing::run_dicesim("info " + prism);
  EXPECT_NE(info.out.find("alike by design    1, 2, 3 | 4, 5"), std::string::npos) << info.out;
}

// The tie: lying on the cut corner, no face is up. The cut is read as its own outcome (7), never
// as whichever of 4, 5, 6 comes first in face order; 4, 5, 6 stay alike (and 1, 2, 3).
TEST(ReadTies, ACutCornerIsItsOwnOutcome) {
  const std::string path = chipped_scene();
  const DieModel m = model_of(path);
  ASSERT_EQ(m.own_read_faces.size(), 1u);
  const int cut = m.own_read_faces[0];
  EXPECT_EQ(m.face_labels[static_cast<std::size_t>(cut)], 7);
  EXPECT_EQ(resting_outcome_label(m, cut), 7);
  EXPECT_EQ(alike_groups(m), (Groups{{1, 2, 3}, {4, 5, 6}}));
  for (const std::string fidelity : {"static", "paper"}) {
    const DieModel f = model_of(path, {"sim.fidelity=\"" + fidelity + "\""});
    RunConfig cfg;
    cfg.seed = 5;
    cfg.tosses = 40000;
    cfg.threads = 2;
    const RunCounts c = run_tosses(f, cfg);
    ASSERT_EQ(c.faces.size(), 7u);
    EXPECT_GT(c.faces[6], 100u) << fidelity << ": the cut must be landed on for the test to mean anything";
    const std::vector<std::uint64_t> low = {c.faces[3], c.faces[4], c.faces[5]};
    EXPECT_GT(chi2_uniform(low).p_value, 1e-3) << fidelity << ": 4, 5, 6 = " << low[0] << ", " << low[1] << ", " << low[2];
  }
  const testing::CliRun info = testing::run_dicesim("info " + path);
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_NE(info.out.find("resting on face -> outcome read"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("reads its own label 7"), std::string::npos) << info.out;
  const auto j = nlohmann::json::parse(testing::run_dicesim("info " + path + " --json").out);
  EXPECT_EQ(j["faces"][cut]["reads"], 7);
  EXPECT_TRUE(j["faces"][cut]["reads_own"].get<bool>());
  EXPECT_EQ(j["alike"]["groups"], nlohmann::json({{1, 2, 3}, {4, 5, 6}}));
}

// The cut labelled 1 as well (the label of +z): no outcome of its own, so the scene must settle it.
TEST(ReadTies, ATieTheSceneLeavesOpenIsRefused) {
  const std::string path = chipped_scene(",\n          { normal = [1, 1, 1], label = 1 }");
  try {
    (void)model_of(path);
    FAIL() << "a tie between faces 4, 5, 6 with no outcome of its own must be refused";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("equally near up"), std::string::npos) << what;
    EXPECT_NE(what.find("label 1"), std::string::npos) << what;
  }
  testing::expect_bad_input(testing::run_dicesim("toss " + path + " -n 10"), {"equally near up", "labels 5, 4, 6"});
}

}  // namespace
}  // namespace dicesim

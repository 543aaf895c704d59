// `impulse` against dice thrown by hand by others (data/experiments/, docs/real-throws.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fidelity_test_util.hpp"
#include "sim/study/equivalence.hpp"

using namespace dicesim;

namespace {

struct Measured {
  double x_over_y, p;
  std::uint64_t n;
};

std::vector<Measured> square_cuboids() {
  std::ifstream in(std::string(DICESIM_SOURCE_DIR) + "/data/experiments/square-cuboids.csv");
  std::vector<Measured> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'x') continue;  // comments, the header
    std::istringstream s(line);
    Measured m{};
    char comma = 0;
    s >> m.x_over_y >> comma >> m.p >> comma >> m.n;
    rows.push_back(m);
  }
  return rows;
}

// The share of `tosses` showing a square face (+z or -z) of scenes/dice/steel-cuboid.toml made
// y x y x (x/y) y with y = 16 mm, thrown as every die scene is (the default throw).
double square_share(double x_over_y, Fidelity f, std::uint64_t tosses) {
  char size[96];
  std::snprintf(size, sizeof size, "die.size=[0.016, 0.016, %.17g]", 0.016 * x_over_y);
  const DieModel m = compile(dicesim::testing::with_fidelity(
      load_scene(std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/steel-cuboid.toml", {size}), f));
  const RunCounts c = dicesim::testing::run(m, tosses, 1);
  EXPECT_EQ(c.settled, tosses) << x_over_y;
  const std::uint64_t square = c.faces[static_cast<std::size_t>(m.face_outcome[4])] +
                               c.faces[static_cast<std::size_t>(m.face_outcome[5])];
  return double(square) / double(c.settled);
}

}  // namespace

// Fifteen steel square cuboids rolled by hand (Mathematical Gazette 2013, Table 1; 275-1011 rolls
// each): the share showing a square face runs from 0.92 (a slab, x/y = 0.47) to 0.006 (a post,
// 2.65). `impulse` with the default throw is equivalent to every one of them within 0.13: two
// one-sided tests at alpha = 0.05 each, Holm-corrected across the fifteen. The widest today is
// x/y = 0.75 (0.638 against 0.548). 0.13 is not derived: it is the round margin today's model
// meets (0.09 fails), so this guards against moving further from the rolls, not a claim of 0.13.
// `static` (the die placed, not thrown) fails it by far: a slab shows its square face 0.61 of the
// time against the rolls' 0.92.
TEST(RealThrows, HandRolledSteelCuboidsAreEquivalentWithinAMargin) {
  const std::vector<Measured> rolls = square_cuboids();
  ASSERT_EQ(rolls.size(), 15u);
  constexpr double kMargin = 0.13, kAlpha = 0.05;
  constexpr std::uint64_t kTosses = 2000;
  std::vector<double> p;
  std::string table;
  for (const Measured& r : rolls) {
    const double sim = square_share(r.x_over_y, Fidelity::Impulse, kTosses);
    const double se = std::sqrt(sim * (1 - sim) / kTosses + r.p * (1 - r.p) / double(r.n));
    p.push_back(tost(sim - r.p, se, kMargin, kAlpha).tost_p);
    table += std::to_string(r.x_over_y) + ": " + std::to_string(sim) + " against " + std::to_string(r.p) + "\n";
  }
  const std::vector<double> holm = holm_adjust(p);
  for (std::size_t i = 0; i < rolls.size(); ++i) EXPECT_LE(holm[i], kAlpha) << "x/y " << rolls[i].x_over_y << "\n" << table;
  // The static answer is no answer here: placed dice miss the slab's rolls by 0.3.
  EXPECT_LT(square_share(0.47, Fidelity::Static, kTosses), rolls[0].p - 0.25);
}

// binom4, printed and thrown by hand by Baktash et al. (404 throws: 4, 119, 167, 104, 10), pooled by
// mirror pairs as its mirror images are not told apart: 1 + 5, 2 + 4, 3. `impulse` with the default
// throw reads 0.036 / 0.588 / 0.377 at 2000 tosses against the throws' 0.035 / 0.552 / 0.413,
// equivalent within 0.10 (two one-sided tests at alpha = 0.05, Holm across the three). 0.10 is not
// derived: it is a round margin today's model meets (0.02 fails); the throws' own 95% half-width,
// up to 0.048, keeps any margin from being much tighter. `static` fails it (1 + 5: 0.136).
TEST(RealThrows, PrintedBinom4IsEquivalentWithinAMargin) {
  std::ifstream in(std::string(DICESIM_SOURCE_DIR) + "/data/experiments/binom4.csv");
  std::vector<std::uint64_t> thrown(5, 0);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'l') continue;
    const std::size_t comma = line.find(',');
    thrown[static_cast<std::size_t>(std::stoi(line.substr(0, comma)) - 1)] = std::stoull(line.substr(comma + 1));
  }
  const std::uint64_t n_thrown = thrown[0] + thrown[1] + thrown[2] + thrown[3] + thrown[4];
  ASSERT_EQ(n_thrown, 404u);
  const std::vector<double> rolled = {double(thrown[0] + thrown[4]) / n_thrown, double(thrown[1] + thrown[3]) / n_thrown,
                                      double(thrown[2]) / n_thrown};
  auto pooled = [](Fidelity f) {
    const DieModel m = compile(dicesim::testing::with_fidelity(
        load_scene(std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/binom4.toml"), f));
    const RunCounts c = dicesim::testing::run(m, 2000, 1);
    EXPECT_EQ(c.settled, 2000u);
    const auto& k = c.faces;  // label order: 1, 2, 3, 4, 5, then the faces it cannot rest on
    const double n = double(c.settled);
    return std::vector<double>{double(k[0] + k[4]) / n, double(k[1] + k[3]) / n, double(k[2]) / n};
  };
  const std::vector<double> sim = pooled(Fidelity::Impulse);
  std::vector<double> p;
  for (std::size_t i = 0; i < 3; ++i) {
    const double se = std::sqrt(sim[i] * (1 - sim[i]) / 2000 + rolled[i] * (1 - rolled[i]) / double(n_thrown));
    p.push_back(tost(sim[i] - rolled[i], se, 0.10, 0.05).tost_p);
  }
  const std::vector<double> holm = holm_adjust(p);
  for (std::size_t i = 0; i < 3; ++i)
    EXPECT_LE(holm[i], 0.05) << "pair " << i << ": " << sim[i] << " against " << rolled[i];
  EXPECT_GT(pooled(Fidelity::Static)[0], rolled[0] + 0.08);  // placed, not thrown: the narrow ends far too often
}

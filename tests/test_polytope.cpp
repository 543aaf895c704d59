// Any convex die in every fidelity (issue 11, the dynamics side): topology and outcomes, fair
// regular solids give 1/N in static, paper and impulse, static equals the Gauss-map basins
// computed independently, a loaded d20 favours the face opposite its slab, a d4 reads the face
// down, rounding lowers the contact point, and the gyroscopic term of the rest criterion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_runner.hpp"
#include "fidelity_test_util.hpp"
#include "polytopes_for_tests.hpp"
#include "sim/body/outcome.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/fidelity_models.hpp"
#include "sim/models/toss.hpp"
#include "sim/study/statistics.hpp"

using namespace dicesim;
using namespace dicesim::testing;

namespace {

DieModel model_of(const Body& b, Fidelity f = Fidelity::Static) { return compile_body(b, with_fidelity(fair_scene(), f)); }

Body d4() {
  Body b = hull_body(tetrahedron(), 1200.0, "d4");
  b.read_down = true;
  return b;
}

// Opposite faces of a centrally symmetric solid: the face whose normal is -n.
int opposite(const DieModel& m, int f) {
  for (int g = 0; g < m.face_count(); ++g)
    if ((m.face_normals[static_cast<std::size_t>(g)] + m.face_normals[static_cast<std::size_t>(f)]).norm() < 1e-9) return g;
  return -1;
}

}  // namespace

TEST(Polytope, TopologyOutcomesAndRestGeometryOfAnIcosahedron) {
  const DieModel m = model_of(hull_body(icosahedron(), 1200.0, "d20"));
  ASSERT_EQ(m.vertex_count(), 12);
  ASSERT_EQ(m.face_count(), 20);
  EXPECT_EQ(m.outcomes(), 20);
  for (int v = 0; v < 12; ++v) EXPECT_EQ(m.neighbours(v).size(), 5u);
  const double inradius = m.face_height[0];
  for (int f = 0; f < 20; ++f) {
    const std::size_t fi = static_cast<std::size_t>(f);
    EXPECT_EQ(m.face_vertices(f).size(), 3u);
    EXPECT_EQ(m.face_result[fi], opposite(m, f));  // read up: the face opposite the one down
    EXPECT_NEAR(m.face_height[fi], inradius, 1e-15);
    EXPECT_GT(m.face_hold[fi], 0.0);
    // The lowest pass is the die balanced on an edge: COM at the edge's midradius.
    const auto loop = m.face_vertices(f);
    const Vec3 mid = 0.5 * (m.vertices[static_cast<std::size_t>(loop[0])] + m.vertices[static_cast<std::size_t>(loop[1])]);
    EXPECT_NEAR(m.face_escape[fi], mid.norm(), 1e-12);
    EXPECT_LT(m.face_gyro[fi], 1e-12 * m.principal_moments.maxCoeff());  // a regular solid: every axis principal
  }
  // Grouped labels: two labels only (odd and even faces) -> two outcomes.
  Body b = hull_body(icosahedron());
  for (std::size_t f = 0; f < b.face_labels.size(); ++f) b.face_labels[f] = 1 + static_cast<int>(f % 2);
  const DieModel g = model_of(b);
  EXPECT_EQ(g.outcomes(), 2);
  const RunCounts r = run(g, 20000, 3);
  EXPECT_EQ(r.faces.size(), 2u);
  EXPECT_EQ(r.faces[0] + r.faces[1], 20000u);
}

TEST(Polytope, FairRegularSolidsAreUniformInStaticPaperAndImpulse) {
  struct Case {
    const char* name;
    Body body;
  };
  const Case cases[] = {{"d4", d4()},
                        {"d6", hull_body(cube(), 1200.0, "d6")},
                        {"d8", hull_body(octahedron(), 1200.0, "d8")},
                        {"d20", hull_body(icosahedron(), 1200.0, "d20")}};
  for (const Case& c : cases) {
    for (const auto& [f, n] : {std::pair{Fidelity::Static, 100000}, std::pair{Fidelity::Paper, 20000},
                               std::pair{Fidelity::Impulse, 3000}}) {
      const DieModel m = model_of(c.body, f);
      const RunCounts r = run(m, static_cast<std::uint64_t>(n), 11);
      ASSERT_EQ(static_cast<int>(r.faces.size()), m.face_count()) << c.name;
      EXPECT_EQ(r.settled + r.unresolved, static_cast<std::uint64_t>(n)) << c.name;
      EXPECT_LE(r.unresolved, static_cast<std::uint64_t>(n) / 500) << c.name << " " << to_string(f);
      // 12 tests: 1e-3 each keeps the family's false-alarm rate near 1%.
      const ChiSquare chi = chi2_uniform(r.faces);
      EXPECT_EQ(chi.dof, m.face_count() - 1);
      EXPECT_GT(chi.p_value, 1e-3) << c.name << " " << to_string(f) << " chi2 " << chi.statistic;
    }
  }
}

// The Gauss-map basins of an irregular uniform hull by a different method: steepest descent of
// the support function h(u) = max_i v_i . u (the COM height standing with down direction u) on
// the sphere by small steps (1 mrad) along minus the least-norm element of its epsilon-
// subdifferential (the tangential parts of the corners within epsilon of the lowest), the way a
// nonsmooth minimiser would, instead of the model's corner -> edge -> face events.
TEST(Polytope, StaticOfAnIrregularHullEqualsItsGaussMapBasins) {
  const DieModel m = model_of(hull_body(irregular()));
  const int nf = m.face_count();
  int stable = 0;
  for (int f = 0; f < nf; ++f) stable += m.face_hold[static_cast<std::size_t>(f)] >= 0.0;
  ASSERT_GE(stable, 3);
  ASSERT_LT(stable, nf);  // some faces cannot hold the COM: the roll must go on from them
  const double R = m.bounding_radius;
  // The least-norm point of the convex hull of 2-D-ish vectors g (all tangent to the sphere at u):
  // a point, a segment's foot, or 0 if some triangle contains 0.
  const auto least_norm = [](const std::vector<Vec3>& g) {
    Vec3 best = g[0];
    for (std::size_t i = 0; i < g.size(); ++i) {
      if (g[i].norm() < best.norm()) best = g[i];
      for (std::size_t j = i + 1; j < g.size(); ++j) {
        const Vec3 d = g[j] - g[i];
        const double t = -g[i].dot(d) / d.squaredNorm();
        if (t > 0.0 && t < 1.0 && (g[i] + t * d).norm() < best.norm()) best = g[i] + t * d;
        for (std::size_t k = j + 1; k < g.size(); ++k) {
          const Vec3 n = d.cross(g[k] - g[i]);
          const double a = n.dot(g[i].cross(g[j])), b = n.dot(g[j].cross(g[k])), c = n.dot(g[k].cross(g[i]));
          if ((a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0)) best = Vec3::Zero();
        }
      }
    }
    return best;
  };
  const auto descend = [&](Vec3 u) {
    double step = 1e-3;  // halved whenever it has converged at this step, down to 1e-9
    std::vector<Vec3> g;
    for (int it = 0; it < 20000 && step > 1e-9; ++it) {
      double top = -1e300;
      for (const Vec3& v : m.vertices) top = std::max(top, v.dot(u));
      g.clear();
      for (const Vec3& v : m.vertices)
        if (v.dot(u) >= top - 2.0 * step * R) g.push_back(v - v.dot(u) * u);
      const Vec3 d = least_norm(g);
      if (d.norm() <= 1e-9 * R) {
        step *= 0.5;
        continue;
      }
      u = (u - step * d.normalized()).normalized();
    }
    int best = 0;
    for (int f = 1; f < nf; ++f)
      if (m.face_normals[static_cast<std::size_t>(f)].dot(u) > m.face_normals[static_cast<std::size_t>(best)].dot(u)) best = f;
    return best;
  };
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  const int n = 2000;
  int agree = 0;
  std::vector<std::uint64_t> by_flow(static_cast<std::size_t>(nf), 0);
  for (int i = 0; i < n; ++i) {
    const Vec3 down = Vec3(normal(rng), normal(rng), normal(rng)).normalized();  // body frame
    const Mat3 R = Eigen::Quaterniond::FromTwoVectors(down, -Vec3::UnitZ()).toRotationMatrix();
    const int a = quasi_static_down_face(m, R, 0.5), b = descend(down);
    ASSERT_GE(a, 0);
    EXPECT_GE(m.face_hold[static_cast<std::size_t>(a)], 0.0);  // only a face that holds the COM
    agree += a == b;
    ++by_flow[static_cast<std::size_t>(m.face_result[static_cast<std::size_t>(b)])];
  }
  // Directions within a step of a basin boundary could differ (none did at 1 mrad and halving).
  EXPECT_GE(agree, n - n / 200) << "of " << n;
  // The static fidelity's counts (its own Philox orientations) against the flow's basin areas:
  // homogeneity of the two samples.
  const RunCounts r = run(m, 60000, 2);
  // The lattice probabilities of `info` agree with the tosses too (chi-square vs their p).
  const std::vector<double> lattice = static_face_probabilities(m, 100000);
  std::vector<double> by_label(static_cast<std::size_t>(m.outcomes()), 0.0);
  for (int f = 0; f < nf; ++f) by_label[static_cast<std::size_t>(m.face_outcome[static_cast<std::size_t>(f)])] += lattice[static_cast<std::size_t>(f)];
  EXPECT_GT(chi2_against(r.faces, by_label).p_value, 1e-3);
  // And the flow's basin areas (its own random directions) agree with both.
  std::vector<std::uint64_t> flow_by_label(by_label.size(), 0);
  for (int f = 0; f < nf; ++f)
    flow_by_label[static_cast<std::size_t>(m.face_outcome[static_cast<std::size_t>(f)])] += by_flow[static_cast<std::size_t>(f)];
  EXPECT_GT(chi2_against(flow_by_label, by_label).p_value, 1e-3);
}

TEST(Polytope, LoadedD20FavoursTheFaceOppositeItsSlab) {
  Body b = hull_body(icosahedron(), 1200.0, "d20");
  const std::size_t heavy = 7;
  load_face(b, heavy, 0.3, 20000.0);
  for (Fidelity f : {Fidelity::Static, Fidelity::Impulse}) {
    const DieModel m = model_of(b, f);
    const int up = m.face_result[heavy];
    const RunCounts r = run(m, f == Fidelity::Static ? 40000 : 3000, 4);
    const std::uint64_t fav = r.faces[static_cast<std::size_t>(m.face_outcome[static_cast<std::size_t>(up)])];
    for (std::size_t k = 0; k < r.faces.size(); ++k) {
      if (k == static_cast<std::size_t>(m.face_outcome[static_cast<std::size_t>(up)])) continue;
      EXPECT_GT(fav, r.faces[k]) << to_string(f);
    }
    // Above the fair 1/20 (Wilson 99.9% lower bound).
    EXPECT_GT(wilson_interval(fav, r.settled, 3.29).lo, 1.0 / 20.0) << to_string(f);
  }
}

TEST(Polytope, D4ReadsTheFaceDown) {
  const Body b = d4();
  for (Fidelity fid : {Fidelity::Static, Fidelity::Paper, Fidelity::Impulse, Fidelity::Stepped}) {
    const DieModel m = model_of(b, fid);
    for (int f = 0; f < 4; ++f) {
      // At rest on face f, tilted slightly: it settles on f and reads f.
      const Mat3 R = Eigen::AngleAxisd(0.05, Vec3(1, 2, 0).normalized()).toRotationMatrix() *
                     Eigen::Quaterniond::FromTwoVectors(m.face_normals[static_cast<std::size_t>(f)], -Vec3::UnitZ()).toRotationMatrix();
      InitialState init;
      init.orientation = R * m.geo_to_body;
      double low = 0.0;
      for (const Vec3& v : m.vertices) low = std::min(low, (R * v).z());
      init.com_position = Vec3(0.0, 0.0, -low + (fid == Fidelity::Paper ? 0.001 : 0.0));
      const TossResult r = toss_from(m, init);
      ASSERT_EQ(r.status, TossStatus::Settled) << to_string(fid);
      EXPECT_EQ(r.face_index, f) << to_string(fid);
      EXPECT_EQ(r.face, m.face_labels[static_cast<std::size_t>(r.face_index)]);
    }
  }
  // Reading down: on the floor the read face's normal points down.
  const DieModel m = model_of(b);
  const Mat3 R = Eigen::Quaterniond::FromTwoVectors(m.face_normals[2], -Vec3::UnitZ()).toRotationMatrix();
  EXPECT_EQ(read_face_index(m, R), 2);
}

TEST(Polytope, RoundingLowersEveryContactByTheRadius) {
  Body b = hull_body(icosahedron(0.013), 1200.0, "d20");
  b.shape.rounding = 0.002;
  const DieModel m = model_of(b, Fidelity::Impulse);
  const DieModel sharp = model_of(hull_body(icosahedron(0.013)), Fidelity::Impulse);
  EXPECT_NEAR(m.bounding_radius, sharp.bounding_radius + 0.002, 1e-15);
  for (std::size_t f = 0; f < 20; ++f) {
    EXPECT_NEAR(m.face_height[f], sharp.face_height[f] + 0.002, 1e-15);
    EXPECT_NEAR(m.face_escape[f], sharp.face_escape[f] + 0.002, 1e-15);
  }
  // Falling straight down face-first from 1 cm: the contact search meets the floor when the
  // core's lowest corners are `rounding` above it.
  RigidState s;
  s.R = Eigen::Quaterniond::FromTwoVectors(m.face_normals[0], -Vec3::UnitZ()).toRotationMatrix();
  s.position = Vec3(0, 0, m.face_height[0] + 0.01);
  const Flight fl(m, s);
  const ContactSearch c = fl.next_contact(1.0);
  ASSERT_EQ(c.outcome, ContactSearch::Outcome::Contact);
  EXPECT_NEAR(c.t, std::sqrt(2.0 * 0.01 / m.gravity), 1e-6);
  const RigidState at = fl.state(c.t);
  EXPECT_NEAR(corner_height(m, at, c.vertex), 0.0, 1e-9 * m.bounding_radius);
  EXPECT_NEAR(at.position.z() + at.R.row(2).dot(m.vertices[static_cast<std::size_t>(c.vertex)]), 0.002, 1e-9);
  EXPECT_EQ(touching_corners(m, at, 1e-9).n, 3);
  EXPECT_NEAR(contact_point(m, at.R, c.vertex).z(), at.R.row(2).dot(m.vertices[static_cast<std::size_t>(c.vertex)]) - 0.002, 1e-15);
}

// A die lying flat on a face whose normal is not principal, spinning about the vertical: the
// floor must supply the torque w^2 |n x I n|; beyond m g face_hold it lifts an edge, so the
// rest criterion must not call it lying flat (and a slow spin is fine).
TEST(Polytope, GyroscopicTermOfTheRestCriterion) {
  Body b = hull_body(irregular());
  for (double& mu : b.vertex_friction) mu = 0.0;  // friction is not what tips it here
  DieModel m = model_of(b, Fidelity::Impulse);
  int f = -1;
  for (int g = 0; g < m.face_count(); ++g)
    if (m.face_hold[static_cast<std::size_t>(g)] > 0.0 && (f < 0 || m.face_gyro[static_cast<std::size_t>(g)] > m.face_gyro[static_cast<std::size_t>(f)])) f = g;
  ASSERT_GE(f, 0);
  const std::size_t fi = static_cast<std::size_t>(f);
  ASSERT_GT(m.face_gyro[fi], 1e-3 * m.principal_moments.maxCoeff());
  const double w_lift = std::sqrt(m.mass * m.gravity * m.face_hold[fi] / m.face_gyro[fi]);
  for (double& e : m.face_escape) e = 0.0;  // take the energy rule out: only the lying-flat rule can answer
  RigidState s;
  s.R = Eigen::Quaterniond::FromTwoVectors(m.face_normals[fi], -Vec3::UnitZ()).toRotationMatrix();
  s.position = Vec3(0, 0, m.face_height[fi]);
  s.omega = Vec3(0, 0, 0.5 * w_lift);
  m.max_escape = 1e300;  // (the cheap pre-check needs some headroom)
  EXPECT_EQ(rest_face_down(m, s, 0.5), f);
  s.omega = Vec3(0, 0, 1.5 * w_lift);
  EXPECT_EQ(rest_face_down(m, s, 0.5), -1);
}

// The ready scenes (scenes/dice/): every fair preset is uniform in `static` (chi-square on N - 1
// dof), its lattice p_static sums to 1 and is 1/N per face, a d4 reads down, and the loaded d20
// favours one face well above 1/20.
TEST(Polytope, ReadyScenesInStatic) {
  const std::string dir = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/";
  for (const char* name : {"d4", "d6", "d8", "d10", "d12", "d20"}) {
    const DieModel m = compile(with_fidelity(load_scene(dir + name + ".toml"), Fidelity::Static));
    EXPECT_EQ(m.read_down, std::string(name) == "d4") << name;
    const RunCounts r = run(m, 60000, 8);
    ASSERT_EQ(static_cast<int>(r.faces.size()), m.outcomes()) << name;
    const ChiSquare chi = chi2_uniform(r.faces);
    EXPECT_EQ(chi.dof, m.outcomes() - 1);
    EXPECT_GT(chi.p_value, 1e-3) << name << " chi2 " << chi.statistic;
    const std::vector<double> p = static_face_probabilities(m, 50000);
    double sum = 0.0;
    for (double x : p) {
      sum += x;
      EXPECT_NEAR(x, 1.0 / m.face_count(), 2e-3) << name;
    }
    EXPECT_NEAR(sum, 1.0, 1e-12) << name;
  }
  const DieModel m = compile(with_fidelity(load_scene(dir + "loaded-d20.toml"), Fidelity::Static));
  const RunCounts r = run(m, 40000, 8);
  // The slab is under label 19; the face opposite it, label 2, comes up most (scene's comment).
  const std::size_t two = static_cast<std::size_t>(
      std::find(m.outcome_labels.begin(), m.outcome_labels.end(), 2) - m.outcome_labels.begin());
  ASSERT_LT(two, r.faces.size());
  for (std::size_t k = 0; k < r.faces.size(); ++k) {
    if (k == two) continue;
    EXPECT_GT(r.faces[two], r.faces[k]) << "label " << m.outcome_labels[k];
  }
  EXPECT_GT(wilson_interval(r.faces[two], r.settled, 3.29).lo, 1.0 / 20.0);
}

// The wire carries six outcomes until the next issue: distributed commands refuse any other die
// (exit 2, one message naming the scene, nothing on stdout); `toss` and `info` take it.
// Distributed commands take any die the wire carries (1 to 120 outcomes; the d20 runs are in the
// integration scenarios, which have a network of their own); beyond that they refuse, exit 2,
// before anything is opened or started.
TEST(Polytope, DistributedCommandsRefuseADieBeyondTheWiresOutcomes) {
  const std::string d20 = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/d20.toml";
  const std::string prism = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/prism3.toml";
  for (const std::string cmd : {"run", "aggregate"}) {
    const CliRun r = run_dicesim(cmd + " " + prism + " --set die.sides=130 -n 10");
    EXPECT_EQ(r.code, 2) << cmd;
    EXPECT_TRUE(r.out.empty()) << cmd;
    EXPECT_NE(r.err.find("1 to 120 outcomes"), std::string::npos) << cmd << ": " << r.err;
    EXPECT_NE(r.err.find("prism3.toml"), std::string::npos) << cmd;
  }
  const CliRun toss = run_dicesim("toss " + d20 + " -n 2000 --json --set sim.fidelity=\"static\"");
  ASSERT_EQ(toss.code, 0) << toss.err;
  const auto j = nlohmann::json::parse(toss.out);
  EXPECT_EQ(j["faces"].size(), 20u);
  EXPECT_EQ(j["chi2_uniform"]["dof"], 19);
  const CliRun info = run_dicesim("info " + d20 + " --json");
  ASSERT_EQ(info.code, 0) << info.err;
  const auto k = nlohmann::json::parse(info.out);
  EXPECT_EQ(k["face_count"], 20);
  EXPECT_EQ(k["vertex_count"], 12);
  ASSERT_EQ(k["faces"].size(), 20u);
  for (const auto& f : k["faces"]) {
    EXPECT_TRUE(f["stable"].get<bool>());
    EXPECT_NEAR(f["p_static"].get<double>(), 0.05, 2e-3);
    EXPECT_GT(f["area"].get<double>(), 0.0);
    EXPECT_EQ(f["normal"].size(), 3u);
  }
}

// The Body contract (sim/body/body.hpp): every shape kind reduces to a ConvexShape whose faces
// are planar, counter-clockwise seen from outside, with outward unit normals.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "sim/body/body.hpp"
#include "sim/body/hull.hpp"
#include "sim/body/labels.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/body/shape.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {
namespace {

void expect_well_formed(const ConvexShape& s) {
  ASSERT_EQ(s.faces.size(), s.normals.size());
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& v : s.vertices) centroid += v;
  centroid /= static_cast<double>(s.vertices.size());
  for (std::size_t f = 0; f < s.faces.size(); ++f) {
    const auto& loop = s.faces[f];
    ASSERT_GE(loop.size(), 3u);
    const Vec3& n = s.normals[f];
    EXPECT_NEAR(n.norm(), 1.0, 1e-12);
    const double d = n.dot(s.vertices[loop[0]]);
    EXPECT_GT(d, n.dot(centroid)) << "face " << f << " normal points inward";
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const Vec3& a = s.vertices[loop[k]];
      const Vec3& b = s.vertices[loop[(k + 1) % loop.size()]];
      const Vec3& c = s.vertices[loop[(k + 2) % loop.size()]];
      EXPECT_NEAR(n.dot(a), d, 1e-12) << "face " << f << " is not planar";
      EXPECT_GT((b - a).cross(c - b).dot(n), 0.0) << "face " << f << " is not counter-clockwise";
    }
  }
}

TEST(Body, BoxShapeFacesAreOutwardCounterClockwiseAndInTheDocumentedOrder) {
  const ConvexShape s = box_shape(Vec3(0.01, 0.02, 0.03));
  ASSERT_EQ(s.vertices.size(), 8u);
  ASSERT_EQ(s.faces.size(), 6u);
  expect_well_formed(s);
  for (int f = 0; f < 6; ++f) {
    Vec3 n = Vec3::Zero();
    n[f / 2] = f % 2 == 0 ? 1.0 : -1.0;
    EXPECT_EQ(s.normals[f], n) << "face order is +x, -x, +y, -y, +z, -z";
  }
  for (int c = 0; c < 8; ++c)
    for (int a = 0; a < 3; ++a) EXPECT_EQ(s.vertices[c][a] > 0.0, ((c >> a) & 1) != 0);
}

TEST(Body, BoxBodyCarriesLabelsMassAndPerVertexMaterials) {
  SceneDef scene = parse_scene(R"(
[materials.steel]
density = 7848.0
restitution = 0.487
friction = 0.2
[die]
material = "steel"
size = [0.03, 0.03, 0.03]
)", "test");
  const Body b = build_body(scene, "test");
  EXPECT_EQ(b.kind, "box");
  EXPECT_EQ(b.face_labels, (std::vector<int>{2, 5, 3, 4, 1, 6}));
  EXPECT_NEAR(b.mass.mass, 7848.0 * 2.7e-5, 1e-12);
  ASSERT_EQ(b.vertex_restitution.size(), 8u);
  for (double e : b.vertex_restitution) EXPECT_NEAR(e, 0.487, 1e-12);
  for (double mu : b.vertex_friction) EXPECT_NEAR(mu, 0.2, 1e-12);
}

}  // namespace
}  // namespace dicesim

// ---- Every shape kind -------------------------------------------------------------------------
namespace dicesim {
namespace {

Body body_of(const std::string& die_keys, const std::string& extra = "") {
  return build_body(parse_scene("[materials.plastic]\ndensity = 1200.0\nrestitution = 0.4\nfriction = 0.5\n" + extra +
                                    "[die]\nmaterial = \"plastic\"\n" + die_keys,
                                "test"),
                    "test");
}

int euler_characteristic(const ConvexShape& s) {
  std::size_t edges = 0;
  for (const auto& f : s.faces) edges += f.size();
  return static_cast<int>(s.vertices.size()) - static_cast<int>(edges / 2) + static_cast<int>(s.faces.size());
}

struct PresetCase {
  const char* shape;
  std::size_t vertices, faces, corners_per_face;
  int first_label, opposite_sum;  // opposite_sum 0: no opposite faces (d4)
};

TEST(BodyShapes, PresetsAreWellFormedWithStandardLabels) {
  const PresetCase cases[] = {{"d4", 4, 4, 3, 1, 0},    {"d6", 8, 6, 4, 1, 7},     {"d8", 6, 8, 3, 1, 9},
                              {"d10", 12, 10, 4, 0, 9}, {"d12", 20, 12, 5, 1, 13}, {"d20", 12, 20, 3, 1, 21}};
  for (const PresetCase& c : cases) {
    SCOPED_TRACE(c.shape);
    const double size = 0.02;
    const Body b = body_of(std::string("shape = \"") + c.shape + "\"\nsize = 0.02\n");
    EXPECT_EQ(b.kind, c.shape);
    ASSERT_EQ(b.shape.vertices.size(), c.vertices);
    ASSERT_EQ(b.shape.faces.size(), c.faces);
    expect_well_formed(b.shape);
    EXPECT_EQ(euler_characteristic(b.shape), 2);
    for (const auto& f : b.shape.faces) EXPECT_EQ(f.size(), c.corners_per_face);
    // Labels: each of first .. first + N - 1 once.
    std::vector<int> sorted = b.face_labels;
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t k = 0; k < sorted.size(); ++k) EXPECT_EQ(sorted[k], c.first_label + static_cast<int>(k));
    EXPECT_EQ(b.read_down, std::string(c.shape) == "d4");
    for (std::size_t f = 0; f < b.shape.faces.size(); ++f) {
      const Vec3& n = b.shape.normals[f];
      const double d = n.dot(b.shape.vertices[b.shape.faces[f][0]]);
      if (c.opposite_sum == 0) {
        EXPECT_NEAR(d, size / 4.0, 1e-14);  // face to centroid: a quarter of the height
        continue;
      }
      const int o = nearest_face(b.shape, -n);
      EXPECT_NEAR(n.dot(b.shape.normals[o]), -1.0, 1e-12) << "opposite faces are parallel";
      EXPECT_NEAR(d - n.dot(b.shape.vertices[b.shape.faces[o][0]]), size, 1e-14) << "size = distance between them";
      EXPECT_EQ(b.face_labels[f] + b.face_labels[o], c.opposite_sum);
    }
    for (double e : b.vertex_restitution) EXPECT_EQ(e, 0.4);
    for (double mu : b.vertex_friction) EXPECT_EQ(mu, 0.5);
  }
}

TEST(BodyShapes, D4FromItsFarthestVertexIsTheSize) {
  const Body b = body_of("shape = \"d4\"\nsize = 0.02\n");
  const Vec3& n = b.shape.normals[0];
  double lowest = 1.0;
  for (const Vec3& v : b.shape.vertices) lowest = std::min(lowest, n.dot(v));
  EXPECT_NEAR(n.dot(b.shape.vertices[b.shape.faces[0][0]]) - lowest, 0.02, 1e-14);
  EXPECT_FALSE(body_of("shape = \"d4\"\nread = \"up\"\n").read_down);
  EXPECT_TRUE(body_of("shape = \"d20\"\nread = \"down\"\n").read_down);
}

TEST(BodyShapes, PrismSidesAndEndsAreLabelledByDirection) {
  const Body b = body_of("shape = \"prism\"\nsides = 3\nradius = 0.01\nlength = 0.06\n");
  ASSERT_EQ(b.shape.vertices.size(), 6u);
  ASSERT_EQ(b.shape.faces.size(), 5u);
  expect_well_formed(b.shape);
  EXPECT_EQ(b.face_labels[nearest_face(b.shape, Vec3(1, 0, 0))], 1);
  EXPECT_EQ(b.face_labels[nearest_face(b.shape, Vec3(std::cos(2.0 * kPi / 3), std::sin(2.0 * kPi / 3), 0))], 2);
  EXPECT_EQ(b.face_labels[nearest_face(b.shape, Vec3(std::cos(4.0 * kPi / 3), std::sin(4.0 * kPi / 3), 0))], 3);
  EXPECT_EQ(b.face_labels[nearest_face(b.shape, Vec3(0, 0, 1))], 4);
  EXPECT_EQ(b.face_labels[nearest_face(b.shape, Vec3(0, 0, -1))], 5);
  const Body many = body_of("shape = \"prism\"\nsides = 40\n");
  EXPECT_EQ(many.shape.faces.size(), 42u);
  expect_well_formed(many.shape);
}

TEST(BodyShapes, HullOfRandomPointsIsWellFormedAndHoldsThemAll) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<Vec3> points;
    for (int i = 0; i < 200; ++i) points.push_back(0.01 * Vec3(g(rng), g(rng), g(rng)).normalized() * (0.5 + 0.5 * std::abs(g(rng))));
    const ConvexShape s = convex_hull(points);
    expect_well_formed(s);
    EXPECT_EQ(euler_characteristic(s), 2);
    for (std::size_t f = 0; f < s.faces.size(); ++f) {
      const double d = s.normals[f].dot(s.vertices[s.faces[f][0]]);
      for (const Vec3& p : points) EXPECT_LE(s.normals[f].dot(p), d + 1e-15);
    }
    // Every hull vertex is one of the points.
    for (const Vec3& v : s.vertices) EXPECT_NE(std::find(points.begin(), points.end(), v), points.end());
  }
}

TEST(BodyShapes, HullMergesCoplanarTrianglesAndDropsPointsOnEdgesAndFaces) {
  std::vector<Vec3> points;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z) points.push_back(0.01 * Vec3(x, y, z));  // corners, edge and face midpoints
  points.push_back(Vec3(0.01, 0.003, 0.004 + 3e-9));  // inside the +x face, within the tolerance
  const ConvexShape s = convex_hull(points);
  EXPECT_EQ(s.vertices.size(), 8u);
  EXPECT_EQ(s.faces.size(), 6u);
  expect_well_formed(s);
  EXPECT_EQ(s.normals[0], Vec3(0, 0, 1)) << "canonical order: top face first";
}

TEST(BodyShapes, HullOfDenseCoplanarGridsIsStillABox) {
  // Many points on every face and edge: qhull's triangulation (Qt) has zero-area triangles here,
  // which are oriented by qhull's own orientation, not by their (zero) cross product.
  std::vector<Vec3> points;
  for (int x = 0; x <= 6; ++x)
    for (int y = 0; y <= 6; ++y)
      for (int z = 0; z <= 6; ++z) points.push_back(Vec3(0.002 * x, 0.003 * y, 0.001 * z));
  const ConvexShape s = convex_hull(points);
  EXPECT_EQ(s.vertices.size(), 8u);
  EXPECT_EQ(s.faces.size(), 6u);
  expect_well_formed(s);
  // Collinear points on a square's edges and a regular polygon's rim.
  std::vector<Vec3> rim;
  for (int k = 0; k < 24; ++k)
    for (double z : {0.0, 0.01}) rim.emplace_back(0.01 * std::cos(2 * kPi * k / 24), 0.01 * std::sin(2 * kPi * k / 24), z);
  for (int k = 0; k < 24; ++k) rim.emplace_back(0.004 * std::cos(2 * kPi * k / 24), 0.004 * std::sin(2 * kPi * k / 24), 0.01);
  const ConvexShape p = convex_hull(rim);
  EXPECT_EQ(p.vertices.size(), 48u);
  EXPECT_EQ(p.faces.size(), 26u);
  expect_well_formed(p);
}

TEST(BodyShapes, CoplanarToleranceIsTheDocumentedOne) {
  // A 20 mm cube (diagonal D = 34.6 mm, tolerance 1e-6 D = 34.6 nm) with the centre of its +x
  // face pushed out by 10 nm (merged: still 6 faces) or by 100 nm (a low pyramid: 4 faces more).
  auto hull_with_bump = [](double bump) {
    std::vector<Vec3> p;
    for (int c = 0; c < 8; ++c) p.push_back(0.01 * Vec3((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1));
    p.push_back(Vec3(0.01 + bump, 0.0, 0.0));
    return convex_hull(p);
  };
  const ConvexShape merged = hull_with_bump(1e-8);
  EXPECT_EQ(merged.faces.size(), 6u);
  EXPECT_EQ(merged.vertices.size(), 8u);
  const ConvexShape pyramid = hull_with_bump(1e-7);
  EXPECT_EQ(pyramid.faces.size(), 9u);
  EXPECT_EQ(pyramid.vertices.size(), 9u);
  expect_well_formed(pyramid);
}

TEST(BodyShapes, HullOfNoisyAndRepeatedPointsIsWellFormed) {
  // A cube grid jittered by about the coplanar tolerance, with every point twice: whatever merges,
  // the result is a closed, outward, planar (within the tolerance) polytope.
  for (int seed = 0; seed < 40; ++seed)
  for (double noise : {1e-10, 1e-8, 3e-8, 1e-7}) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> g(0.0, noise);
    std::vector<Vec3> points;
    const int n = 2 + seed % 4;
    for (int x = 0; x <= n; ++x)
      for (int y = 0; y <= n; ++y)
        for (int z = 0; z <= n; ++z) {
          const Vec3 p = 0.02 / n * Vec3(x, y, z) + Vec3(g(rng), g(rng), g(rng));
          points.push_back(p);
          points.push_back(p);
        }
    const ConvexShape s = convex_hull(points);
    EXPECT_EQ(euler_characteristic(s), 2) << noise;
    // Closed and consistently oriented: every edge once in each direction.
    std::map<std::pair<int, int>, int> edges;
    for (const auto& f : s.faces)
      for (std::size_t k = 0; k < f.size(); ++k) ++edges[{f[k], f[(k + 1) % f.size()]}];
    for (const auto& [e, count] : edges) {
      EXPECT_EQ(count, 1) << "seed " << seed << " noise " << noise;
      EXPECT_EQ(edges.count({e.second, e.first}), 1u) << "seed " << seed << " noise " << noise;
    }
    for (std::size_t f = 0; f < s.faces.size(); ++f) {
      const Vec3& n = s.normals[f];
      double hi = -1.0, lo = 1.0;
      for (int v : s.faces[f]) {
        hi = std::max(hi, n.dot(s.vertices[v]));
        lo = std::min(lo, n.dot(s.vertices[v]));
      }
      EXPECT_LE(hi - lo, 1.01 * kCoplanarTolerance * 0.0347) << "face " << f << " is planar within the tolerance";
      for (const Vec3& p : points) EXPECT_LE(n.dot(p), hi + 2.0 * kCoplanarTolerance * 0.035);
    }
  }
}

TEST(BodyShapes, HullOrderDoesNotDependOnInputOrder) {
  const Body a = body_of("shape = \"d20\"\n");
  std::vector<Vec3> shuffled = a.shape.vertices;
  std::mt19937_64 rng(3);
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  const ConvexShape b = convex_hull(shuffled);
  EXPECT_EQ(b.vertices, a.shape.vertices);
  EXPECT_EQ(b.faces, a.shape.faces);
}

TEST(BodyShapes, HullKeysGiveTheirShapeScaledAndLabelledInFaceOrder) {
  const Body b = body_of(
      "shape = \"hull\"\nscale = 0.001\n"
      "vertices = [[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]]\n");
  ASSERT_EQ(b.shape.faces.size(), 4u);
  EXPECT_NEAR(b.mass.mass, 1200.0 * 1e-6 / 6.0, 1e-15);
  EXPECT_EQ(b.face_labels, (std::vector<int>{1, 2, 3, 4}));
  expect_well_formed(b.shape);
}

TEST(BodyLabels, NearestNormalSharedLabelsAndNumberingOfTheRest) {
  const std::string tet = "shape = \"hull\"\nvertices = [[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0], [0, 0, 0.01]]\n";
  const Body b = body_of(tet +
                         "[[die.labels]]\nnormal = [0, 0, -1]\nlabel = 7\n"
                         "[[die.labels]]\nnormal = [0, -1, 0.1]\nlabel = 7\n");
  EXPECT_EQ(b.face_labels[nearest_face(b.shape, Vec3(0, 0, -1))], 7);
  EXPECT_EQ(b.face_labels[nearest_face(b.shape, Vec3(0, -1, 0))], 7);
  // The other two, in face order: 1 and 2.
  std::vector<int> rest;
  for (std::size_t f = 0; f < 4; ++f)
    if (b.face_labels[f] != 7) rest.push_back(b.face_labels[f]);
  EXPECT_EQ(rest, (std::vector<int>{1, 2}));
  // Presets keep their standard labels except the one named.
  const Body d8 = body_of("shape = \"d8\"\n[[die.labels]]\nnormal = [1, 1, 1]\nlabel = 42\n");
  EXPECT_EQ(d8.face_labels[nearest_face(d8.shape, Vec3(1, 1, 1))], 42);
  EXPECT_EQ(std::count(d8.face_labels.begin(), d8.face_labels.end(), 42), 1);
  // The box: [[die.labels]] on top of [die.faces].
  const Body box = body_of("[[die.labels]]\nnormal = [0, 0, 1]\nlabel = 9\n");
  EXPECT_EQ(box.face_labels, (std::vector<int>{2, 5, 3, 4, 9, 6}));
}

TEST(BodyLabels, RoundedBoxKeepsItsFaceMapByDirection) {
  const Body b = body_of("shape = \"d6\"\nsize = 0.016\nrounding = 0.002\n[die.faces]\n\"+x\" = 9\n");
  const Vec3 dirs[6] = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  const int expected[6] = {9, 5, 3, 4, 1, 6};
  for (int k = 0; k < 6; ++k) EXPECT_EQ(b.face_labels[nearest_face(b.shape, dirs[k])], expected[k]) << k;
  const Body box = body_of("size = [0.02, 0.03, 0.04]\nrounding = 0.001\n");
  for (int k = 0; k < 6; ++k) EXPECT_EQ(box.face_labels[nearest_face(box.shape, dirs[k])], (std::array<int, 6>{2, 5, 3, 4, 1, 6})[k]);
}

TEST(BodyLabels, TwoLabelsOnOneFaceIsAnError) {
  try {
    body_of("shape = \"d6\"\n[[die.labels]]\nnormal = [0, 0, 1]\nlabel = 1\n[[die.labels]]\nnormal = [0.1, 0, 1]\nlabel = 2\n");
    FAIL() << "no error";
  } catch (const SceneError& e) {
    EXPECT_EQ(e.key(), "die.labels[1].normal");
    EXPECT_NE(e.allowed().find("same face"), std::string::npos) << e.what();
    EXPECT_NE(e.allowed().find("die.labels[0]"), std::string::npos) << e.what();
  }
}

TEST(BodyMaterials, RegionsGiveEachVertexTheMaterialAroundIt) {
  // A d8 whose lower half (z < 0) is steel: the bottom corner is steel, the top corner plastic,
  // the four equator corners half and half.
  const Body b = body_of("shape = \"d8\"\n[[die.regions]]\nmaterial = \"steel\"\ncuts = [{normal = [0, 0, 1], offset = 0.0}]\n",
                         "[materials.steel]\ndensity = 7800.0\nrestitution = 0.8\nfriction = 0.1\n");
  for (std::size_t v = 0; v < b.shape.vertices.size(); ++v) {
    const double z = b.shape.vertices[v].z();
    const double expected = z > 1e-9 ? 0.4 : z < -1e-9 ? 0.8 : 0.6;
    EXPECT_NEAR(b.vertex_restitution[v], expected, 1e-9) << "vertex " << v;
  }
}

}  // namespace
}  // namespace dicesim

// ---- Bad input that only the body can see -----------------------------------------------------
namespace dicesim {
namespace {

SceneError body_error(const std::string& die_keys, const std::string& extra = "") {
  try {
    body_of(die_keys, extra);
  } catch (const SceneError& e) {
    return e;
  }
  ADD_FAILURE() << "no SceneError for: " << die_keys;
  return SceneError("", "", "", "");
}

void expect_has(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "'" << part << "' not in: " << text;
}

TEST(BodyErrors, FlatOrDegenerateHulls) {
  const SceneError flat = body_error("shape = \"hull\"\nvertices = [[0,0,0],[0.01,0,0],[0,0.01,0],[0.01,0.01,0]]\n");
  EXPECT_EQ(flat.key(), "die.vertices");
  expect_has(flat.allowed(), "one plane");
  const SceneError line = body_error("shape = \"hull\"\nvertices = [[0,0,0],[0.01,0,0],[0.02,0,0],[0.03,0,0]]\n");
  expect_has(line.allowed(), "one line");
  const SceneError same = body_error("shape = \"hull\"\nvertices = [[0,0,0],[0,0,0],[0,0,0],[0,0,0]]\n");
  expect_has(same.allowed(), "coincide");
}

TEST(BodyErrors, RoundingNotBelowTheInradius) {
  // A d6 of size 0.02 has inradius 0.01.
  const SceneError e = body_error("shape = \"d6\"\nsize = 0.02\nrounding = 0.01\n");
  EXPECT_EQ(e.key(), "die.rounding");
  EXPECT_EQ(e.value(), "0.01");
  expect_has(e.allowed(), "inradius");
  expect_has(e.allowed(), "0.01 m");
  EXPECT_NO_THROW(body_of("shape = \"d6\"\nsize = 0.02\nrounding = 0.0099\n"));
  // A flat box: the inradius is half its thinnest edge.
  const SceneError box = body_error("size = [0.03, 0.03, 0.004]\nrounding = 0.0025\n");
  expect_has(box.allowed(), "0.002 m");
}

TEST(BodyErrors, RegionThatLeavesNothingOfTheDie) {
  const SceneError e = body_error("shape = \"d20\"\nsize = 0.02\n[[die.regions]]\nmaterial = \"plastic\"\n"
                                  "cuts = [{normal = [0, 0, 1], offset = -0.02}]\n");
  EXPECT_EQ(e.key(), "die.regions[0].cuts");
  expect_has(e.allowed(), "no part of the die");
}

std::string write_obj(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

const char* kCubeObj = R"(v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
)";

SceneError obj_error(const std::string& text) {
  const std::string path = write_obj("bad.obj", text);
  const SceneError e = body_error("shape = \"mesh\"\nmesh = \"" + path + "\"\nscale = 0.01\n");
  EXPECT_EQ(e.file(), path);
  return e;
}

TEST(BodyErrors, ObjThatDoesNotParseOrIsNotClosedNamesTheLine) {
  const std::string cube = kCubeObj;
  EXPECT_NO_THROW(body_of("shape = \"mesh\"\nmesh = \"" + write_obj("cube.obj", cube) + "\"\nscale = 0.01\n"));

  const SceneError number = obj_error("v 0 0 x\n" + cube);
  EXPECT_EQ(number.key(), "line 1");
  EXPECT_EQ(number.value(), "v 0 0 x");
  expect_has(number.allowed(), "not a finite number");

  const SceneError index = obj_error(cube + "f 1 2 99\n");
  EXPECT_EQ(index.key(), "line 15");
  expect_has(index.allowed(), "out of range");

  const SceneError statement = obj_error(cube + "curv 0 1 2\n");
  expect_has(statement.allowed(), "unknown OBJ statement 'curv'");

  // Drop the last face: the mesh has a hole.
  const SceneError open = obj_error(cube.substr(0, cube.rfind("f 4 1 5 8")));
  expect_has(open.allowed(), "closed");
  EXPECT_EQ(open.key().rfind("line ", 0), 0u);

  // Reverse one face: inconsistent orientation.
  std::string flipped = cube;
  flipped.replace(flipped.find("f 5 6 7 8"), 9, "f 8 7 6 5");
  const SceneError orient = obj_error(flipped);
  expect_has(orient.allowed(), "consistently oriented");

  // Reverse all faces: inside out.
  std::string inverted;
  std::istringstream in(cube);
  for (std::string l; std::getline(in, l);) {
    if (l[0] == 'f') {
      std::istringstream w(l.substr(2));
      std::vector<std::string> ids;
      for (std::string t; w >> t;) ids.push_back(t);
      std::reverse(ids.begin(), ids.end());
      l = "f";
      for (const auto& t : ids) l += " " + t;
    }
    inverted += l + "\n";
  }
  expect_has(obj_error(inverted).allowed(), "inward");

  // A closed but flat mesh: a square's two sides.
  expect_has(obj_error("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 2 1 4\nf 2 4 3\n").allowed(),
             "no volume");
}

}  // namespace
}  // namespace dicesim

// ---- Ready scenes (scenes/dice/) ---------------------------------------------------------------
namespace dicesim {
namespace {

Body ready(const std::string& name) {
  const std::string path = std::string(DICESIM_SOURCE_DIR) + "/scenes/dice/" + name;
  return build_body(load_scene(path), path);
}

TEST(BodyReadyScenes, EveryDiceSceneBuilds) {
  struct Case {
    const char* file;
    std::size_t faces;
    bool read_down;
    double rounding;
  };
  const Case cases[] = {{"d4.toml", 4, true, 0.0},          {"d6.toml", 6, false, 0.0015},
                        {"d8.toml", 8, false, 0.0},         {"d10.toml", 10, false, 0.0},
                        {"d12.toml", 12, false, 0.0},       {"d20.toml", 20, false, 0.0},
                        {"loaded-d20.toml", 20, false, 0.0}, {"steel-cuboid.toml", 6, false, 0.0},
                        {"prism3.toml", 5, true, 0.0},       {"hollow-d6.toml", 6, false, 0.0}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const Body b = ready(c.file);
    EXPECT_EQ(b.shape.faces.size(), c.faces);
    EXPECT_EQ(b.read_down, c.read_down);
    EXPECT_EQ(b.shape.rounding, c.rounding);
    expect_well_formed(b.shape);
    EXPECT_GT(b.mass.mass, 0.0);
  }
}

TEST(BodyReadyScenes, HollowD6MeshHasItsCavitysMassAndItsHullsFaces) {
  const Body b = ready("hollow-d6.toml");
  EXPECT_EQ(b.kind, "mesh");
  EXPECT_FALSE(b.convex);
  EXPECT_EQ(b.shape.vertices.size(), 8u) << "the cavity's corners are not on the hull";
  EXPECT_EQ(b.shape.faces.size(), 6u);
  // 16^3 - 6^3 = 3880 mm^3 of plastic; the cavity's centre is 3 mm above the cube's.
  EXPECT_NEAR(b.mass.mass, 1180.0 * 3880e-9, 1e-15);
  EXPECT_NEAR(b.mass.com.z(), -216.0 * 3.0 / 3880.0 * 1e-3, 1e-15);
  EXPECT_LE(b.mass.com.head<2>().norm(), 1e-15);
  for (std::size_t f = 0; f < 6; ++f) EXPECT_EQ(b.face_labels[f] + b.face_labels[nearest_face(b.shape, -b.shape.normals[f])], 7);
  EXPECT_EQ(b.face_labels[nearest_face(b.shape, Vec3::UnitZ())], 1);
}

TEST(BodyReadyScenes, LoadedD20IsHeavyTowardsItsSlabFace) {
  const Body fair = ready("d20.toml");
  const Body loaded = ready("loaded-d20.toml");
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  const Vec3 n = Vec3(1.0 / phi, 0.0, -phi).normalized();
  EXPECT_LE(fair.mass.com.norm(), 1e-15);
  // The slab (steel in n.x >= 8 mm) pulls the COM towards the face with normal n.
  EXPECT_GT(loaded.mass.com.dot(n), 1e-4);
  EXPECT_LE((loaded.mass.com - loaded.mass.com.dot(n) * n).norm(), 1e-12) << "and only along n";
  EXPECT_NEAR(loaded.shape.normals[nearest_face(loaded.shape, n)].dot(n), 1.0, 1e-12) << "n is a face normal";
  EXPECT_GT(loaded.mass.mass, fair.mass.mass);
  EXPECT_EQ(loaded.face_labels[nearest_face(loaded.shape, n)], 19) << "as the scene says";
  EXPECT_EQ(loaded.face_labels[nearest_face(loaded.shape, -n)], 2);
  // Its contact corners are steel (those of the slab face) or plastic.
  const int f = nearest_face(loaded.shape, n);
  for (int v : loaded.shape.faces[f]) EXPECT_NEAR(loaded.vertex_restitution[v], 0.6, 1e-12);
}

}  // namespace
}  // namespace dicesim

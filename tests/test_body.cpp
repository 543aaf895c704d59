// The Body contract (sim/body/body.hpp): every shape kind reduces to a ConvexShape whose faces
// are planar, counter-clockwise seen from outside, with outward unit normals.
#include <gtest/gtest.h>

#include "sim/body/body.hpp"
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

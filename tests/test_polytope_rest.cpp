// Rest soundness for any convex die: when `impulse` says "settled", the die really comes to rest
// on a face read as that one. Continued with the contact stepper for 0.5 s (plastic contact with
// friction, the `stepped` physics), the face on the floor never changes to one read otherwise.
// 10^3 tosses per die: fair d4, d8, d20, a long triangular prism, an irregular hull, a rounded d20,
// a loaded d20, and the irregular hull thrown with a fast spin (its face normals are not principal
// axes: the gyroscopic term).
#include <gtest/gtest.h>

#include <string>

#include "fidelity_test_util.hpp"
#include "polytopes_for_tests.hpp"
#include "sim/body/outcome.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"

using namespace dicesim;
using namespace dicesim::testing;

namespace {

struct Case {
  std::string name;
  Body body;
  double spin_sd = 18.0;
};

// The face the die lies on: of the faces that can hold it, the one most nearly down (a face that
// cannot hold the COM, 2.5 mrad from one that can, as the irregular hull has, may point lower
// while the die wobbles on its neighbour); `highest`: its highest corner above the floor.
int face_down(const DieModel& m, const RigidState& s, double& highest) {
  int down = -1;
  for (int f = 0; f < m.face_count(); ++f)
    if (m.face_hold[static_cast<std::size_t>(f)] >= 0.0 &&
        (down < 0 || s.R.row(2).dot(m.face_normals[static_cast<std::size_t>(f)]) <
                         s.R.row(2).dot(m.face_normals[static_cast<std::size_t>(down)])))
      down = f;
  highest = -1.0;
  for (const int v : m.face_vertices(down)) highest = std::max(highest, corner_height(m, s, v));
  return down;
}

void check_rest_soundness(const Case& c, int tosses) {
  SceneDef scene = with_fidelity(fair_scene(), Fidelity::Impulse);
  scene.throw_.spin.components.sd = Vec3::Constant(c.spin_sd);
  const DieModel m = compile_body(c.body, scene, c.name);
  int settled = 0, unresolved = 0;
  for (int i = 0; i < tosses; ++i) {
    RigidState s;
    const TossResult r = toss_to_end(m, 31, static_cast<std::uint64_t>(i), s);
    if (r.status != TossStatus::Settled) {
      ++unresolved;
      continue;
    }
    ++settled;
    // The face impulse settled on (down): what the rest criterion says of the final state.
    const int down = rest_face_down(m, s, 0.5);
    ASSERT_GE(down, 0) << c.name << " toss " << i;
    ASSERT_EQ(result_face(m, down), r.face_index) << c.name << " toss " << i;
    ASSERT_GE(m.face_hold[static_cast<std::size_t>(down)], 0.0) << c.name << ": a face that cannot hold the COM";
    // 0.5 s more of contact dynamics: the face on the floor at the end reads as that face, and the
    // rest criterion never names a face read otherwise on the way. (The die need not lie flat all
    // along: it may still roll onto the face, or a d4 wobble on its corners as a spinning coin does;
    // and settled means its outcome can no longer change, so it may still cross to a neighbouring
    // face that reads the same, as the irregular hull's faces under one face up do: rest.hpp.)
    FixedStepper st(m, 5e-4);
    for (int k = 1; k <= 1000; ++k) {
      st.step(s);
      if (k % 100 != 0) continue;
      // -1 is allowed: a die that was called flat while still sliding fast has more energy than
      // the barrier, and while it wobbles only the friction argument (not checked again) holds.
      const int again = rest_face_down(m, s, 0.5);
      ASSERT_TRUE(again == -1 || resting_outcome_label(m, again) == resting_outcome_label(m, down))
          << c.name << " toss " << i << " after " << k * 5e-4 << " s: " << again;
    }
    // The face on the floor at the end reads as that face. It need not lie flat yet: with
    // restitution in every step (the energy-safe stepper) a die may still rock on it after 0.5 s.
    double highest = 0.0;
    EXPECT_EQ(resting_outcome_label(m, face_down(m, s, highest)), resting_outcome_label(m, down)) << c.name << " toss " << i;
  }
  // Unresolved tosses are counted, not checked here; the irregular hull has ~0.6% (it hits the
  // impact cap: see the report of issue 11), the regular solids none.
  EXPECT_LE(unresolved, tosses / 100) << c.name;
  EXPECT_GT(settled, 0);
}

Body rounded_d20() {
  Body b = hull_body(icosahedron(0.013), 1200.0, "d20");
  b.shape.rounding = 0.002;
  return b;
}

Body loaded_d20() {
  Body b = hull_body(icosahedron(), 1200.0, "d20");
  load_face(b, 3, 0.25, 6000.0);
  return b;
}

Body read_down(Body b) {
  b.read_down = true;
  return b;
}

}  // namespace

TEST(PolytopeRest, RegularSolidsStayOnTheirFace) {
  check_rest_soundness({"d4", read_down(hull_body(tetrahedron(), 1200.0, "d4"))}, 1000);
  check_rest_soundness({"d8", hull_body(octahedron(), 1200.0, "d8")}, 1000);
  check_rest_soundness({"d20", hull_body(icosahedron(), 1200.0, "d20")}, 1000);
}

TEST(PolytopeRest, PrismAndIrregularHullStayOnTheirFace) {
  // Read from the face it rests on, as scenes/dice/prism3.toml: lying on a side it has an edge on top.
  check_rest_soundness({"prism", read_down(hull_body(prism(3, 0.006, 0.04), 1200.0, "prism"))}, 1000);
  check_rest_soundness({"irregular", hull_body(irregular())}, 1000);
}

TEST(PolytopeRest, RoundedAndLoadedStayOnTheirFace) {
  check_rest_soundness({"rounded d20", rounded_d20()}, 1000);
  check_rest_soundness({"loaded d20", loaded_d20()}, 1000);
}

TEST(PolytopeRest, NonPrincipalFastSpinStaysOnItsFace) {
  check_rest_soundness({"irregular, spin sd 60 rad/s", hull_body(irregular()), 60.0}, 1000);
}

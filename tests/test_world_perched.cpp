// A die held still off its rest by the bodies it touches (world_detail::held_still, run_world's
// perched dice): the static-equilibrium test against cases whose answer is known by hand, and a
// toss whose die lands on a box's top, which ends there at once instead of after the half second
// a still die is otherwise watched.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>

#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"
#include "sim/models/world_contacts.hpp"
#include "sim/scene/scene.hpp"

namespace {

using namespace dicesim;
using world_detail::HeldTouch;
using world_detail::held_still;

const std::string kWorld = std::string(DICESIM_SOURCE_DIR) + "/scenes/world/";

// A 16 mm d6 (no rounding), axis-aligned at the origin.
DieModel cube() {
  return compile(parse_scene(R"(
[materials.plastic]
density = 1180.0
restitution = 0.5
friction = 0.3
[die]
shape = "d6"
size = 0.016
material = "plastic"
)", kWorld + "test.toml", {}));
}

RigidState at_rest() {
  RigidState s;
  s.position = Vec3::Zero();
  s.velocity = Vec3::Zero();
  s.omega = Vec3::Zero();
  s.R = Mat3::Identity();
  return s;
}

// The bottom face's corners (x, y in {-h, h}, z = -h) with x in xs, as a touch of normal n.
HeldTouch bottom(const std::array<double, 2>& xs, const Vec3& n, double mu, double h = 0.008) {
  HeldTouch t;
  t.normal = n;
  t.mu = mu;
  for (const double x : xs)
    for (const double y : {-h, h}) t.patch.points[static_cast<std::size_t>(t.patch.n++)] = Vec3(x, y, -h);
  return t;
}

constexpr double kTau = 1e-3;

TEST(WorldPerched, AFaceOnALevelTopIsHeldAnEdgeAloneIsNot) {
  const DieModel d = cube();
  const RigidState s = at_rest();
  const std::array<HeldTouch, 1> face{bottom({-0.008, 0.008}, Vec3::UnitZ(), 0.3)};
  EXPECT_TRUE(held_still(d, s, face, kTau));
  // One edge, off the centre of mass: the die tips about it.
  const std::array<HeldTouch, 1> edge{bottom({0.006, 0.008}, Vec3::UnitZ(), 0.3)};
  EXPECT_FALSE(held_still(d, s, edge, kTau));
  // The same edge with the other half of the face on a second top beside it: held again.
  const std::array<HeldTouch, 2> two{bottom({0.006, 0.008}, Vec3::UnitZ(), 0.3),
                                     bottom({-0.008, -0.006}, Vec3::UnitZ(), 0.3)};
  EXPECT_TRUE(held_still(d, s, two, kTau));
}

TEST(WorldPerched, OnAnInclineFrictionDecides) {
  // A face on a 30 degree incline (tan 30 = 0.577): held where mu exceeds it, sliding where not.
  const DieModel d = cube();
  const double a = 30.0 * M_PI / 180.0;
  RigidState s = at_rest();
  s.R = Eigen::AngleAxisd(-a, Vec3::UnitY()).toRotationMatrix();  // the bottom face turned to the incline
  const Vec3 n = s.R * Vec3::UnitZ();
  const auto on_incline = [&](double mu) {
    HeldTouch t;
    t.normal = n;
    t.mu = mu;
    for (const double x : {-0.008, 0.008})
      for (const double y : {-0.008, 0.008})
        t.patch.points[static_cast<std::size_t>(t.patch.n++)] = s.R * Vec3(x, y, -0.008);
    return std::array<HeldTouch, 1>{t};
  };
  EXPECT_TRUE(held_still(d, s, on_incline(0.70), kTau));
  EXPECT_FALSE(held_still(d, s, on_incline(0.50), kTau));
}

TEST(WorldPerched, InAVTroughTheWallsHoldItAloneBetweenUprightWallsTheyDoNot) {
  // A cube in a V trough, each wall touching one bottom edge, their normals 30 degrees off the
  // vertical: the two normal forces hold the weight with no friction at all. Between upright
  // frictionless walls nothing holds it up.
  const DieModel d = cube();
  const RigidState s = at_rest();
  const double a = 30.0 * M_PI / 180.0;
  const Vec3 left(std::sin(a), 0.0, std::cos(a)), right(-std::sin(a), 0.0, std::cos(a));
  const std::array<HeldTouch, 2> leaning{bottom({-0.008, -0.008}, left, 0.0), bottom({0.008, 0.008}, right, 0.0)};
  EXPECT_TRUE(held_still(d, s, leaning, kTau));
  const std::array<HeldTouch, 2> vertical{bottom({-0.008, -0.008}, Vec3::UnitX(), 0.0),
                                          bottom({0.008, 0.008}, -Vec3::UnitX(), 0.0)};
  EXPECT_FALSE(held_still(d, s, vertical, kTau));
}

// A d6 dropped onto the middle of a 30 cm box's top, 5 cm high: it comes to rest there, on no
// face of the floor. Perched as soon as it lies still and held, the toss ends unresolved then, not
// after kStillTime (0.5 s) of stillness.
TEST(WorldPerched, ADieThatLandsOnABoxEndsThereUnresolvedAtOnce) {
  const DieModel m = compile(parse_scene(R"(
name = "box top"
[materials.wood]
density = 700.0
restitution = 0.3
friction = 0.5
[[obstacles]]
kind = "box"
material = "wood"
centre = [0, 0, 0.025]
size = [0.3, 0.3, 0.05]
[throw.height]
mean = 0.12
sd = 0.01
[throw.velocity]
mean = [0, 0, 0]
sd = [0.05, 0.05, 0.05]
[throw.spin]
sd = [5, 5, 5]
[die]
shape = "d6"
size = 0.016
rounding = 0.001
material = "wood"
[sim]
fidelity = "impulse"
)", kWorld + "test.toml", {}));
  int perched = 0;
  for (std::uint64_t i = 0; i < 40; ++i) {
    RigidState end;
    TossProbe probe;
    probe.final_state = &end;
    const TossResult r = toss(m, 3, i, &probe);
    EXPECT_EQ(r.status, TossStatus::Unresolved) << i;
    EXPECT_GT(end.position.z(), 0.05) << i;  // on the top, not on the floor
    perched += probe.perched == 1;
    EXPECT_LT(r.t_end, 0.5) << i;  // watched still for 0.5 s, it would have ended later
    EXPECT_EQ(end.velocity.norm() + end.omega.norm(), 0.0) << i;  // held: at rest
  }
  EXPECT_EQ(perched, 40);
}

}  // namespace

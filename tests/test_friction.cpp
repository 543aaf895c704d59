// The friction impact law (sim/friction_impact.hpp) and sliding under Coulomb friction.
#include <gtest/gtest.h>

#include <cmath>

#include "fidelity_test_util.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss_random.hpp"

using namespace dicesim;
using namespace dicesim::testing;

namespace {

DieModel slab_model(double e, double mu, double alu_fraction = 0.5) {
  SceneDef s = slab_scene(alu_fraction);
  for (auto& [name, mat] : s.materials) {
    mat.restitution = e;
    mat.friction = mu;
  }
  return compile(s);
}

// A random state with its lowest corner on the floor, approaching it.
RigidState touching_state(const DieModel& m, TossRandom& rng, double spin) {
  RigidState s;
  s.R = uniform_rotation(rng.uniform(), rng.uniform(), rng.uniform());
  double low = 0.0;
  for (const Vec3& v : m.vertices) low = std::min(low, (s.R * v).z());
  s.position = Vec3(0, 0, -low);
  s.velocity = Vec3(rng.normal(), rng.normal(), -3.0 * rng.uniform());
  s.omega = spin * Vec3(rng.normal(), rng.normal(), rng.normal());
  return s;
}

}  // namespace

TEST(FrictionImpact, NeverCreatesEnergy) {
  for (double e : {0.0, 0.5, 1.0})
    for (double mu : {0.0, 0.3, 2.0}) {
      const DieModel m = slab_model(e, mu, 0.3);
      TossRandom rng(11, static_cast<std::uint64_t>(10 * e + mu * 100));
      for (int k = 0; k < 2000; ++k) {
        RigidState s = touching_state(m, rng, k % 2 ? 50.0 : 1000.0);
        const ContactSet c = touching_corners(m, s, 1e-6 * m.bounding_radius);
        const double e0 = kinetic_energy(m, s);
        const ImpactResult r = apply_friction_impact(m, s, c, true);
        ASSERT_TRUE(s.velocity.allFinite() && s.omega.allFinite());
        // Rounding of a 3x3 solve: a few ulps of the energy.
        EXPECT_LE(kinetic_energy(m, s), e0 * (1.0 + 1e-12)) << "e " << e << " mu " << mu;
        EXPECT_GE(r.normal_impulse, -1e-12 * m.mass);
      }
    }
}

TEST(FrictionImpact, FrictionlessLimitIsTheNewtonImpulse) {
  const DieModel m = slab_model(1.0, 0.0, 0.3);
  TossRandom rng(12, 0);
  for (int k = 0; k < 1000; ++k) {
    RigidState s = touching_state(m, rng, 20.0);
    const ContactSet c = touching_corners(m, s, 1e-6 * m.bounding_radius);
    ASSERT_EQ(c.n, 1);
    const double e0 = kinetic_energy(m, s);
    apply_friction_impact(m, s, c, true);
    EXPECT_NEAR(kinetic_energy(m, s), e0, 1e-12 * e0);  // e = 1, no friction: elastic
  }
}

TEST(FrictionImpact, PlasticImpactStopsTheNormalVelocity) {
  const DieModel m = slab_model(0.0, 0.3);
  TossRandom rng(13, 0);
  for (int k = 0; k < 1000; ++k) {
    RigidState s = touching_state(m, rng, 20.0);
    const ContactSet c = touching_corners(m, s, 1e-6 * m.bounding_radius);
    const double before = corner_velocity(m, s, c.vertex[0]).z();
    if (before >= 0.0) continue;
    apply_friction_impact(m, s, c, true);
    // The point never keeps approaching; plastic: it does not rebound either unless friction
    // slip couples into the normal direction (then the rebound is bounded by the approach speed).
    const double after = corner_velocity(m, s, c.vertex[0]).z();
    EXPECT_GE(after, -1e-9 * std::abs(before));
    EXPECT_LE(after, std::abs(before) * (1.0 + 1e-9));
  }
}

// One corner, perfectly plastic: the impulse P = m dv must satisfy Coulomb's law, however
// strongly W couples slip and normal (there the fixed point on the slip direction cycles and the
// angle root-finder takes over): the normal velocity is stopped; sliding -> |P_t| = mu P_n and
// P_t opposite the final slip (maximal dissipation); sticking -> no final slip, P inside the cone.
// The only exception allowed is a jam (no sliding direction stops the point: Painleve), where the
// projected Gauss-Seidel fallback gives its best; that is rarer than 1 in 1000 random states
// (the former fixed-point-then-PGS solve broke Coulomb in ~20% of sliding impacts).
TEST(FrictionImpact, OneCornerPlasticImpulseObeysCoulomb) {
  int sliding = 0, total = 0, broken = 0;
  for (double mu : {0.1, 0.3, 1.0}) {
    const DieModel m = slab_model(0.0, mu, 0.3);
    TossRandom rng(14, static_cast<std::uint64_t>(mu * 100));
    for (int k = 0; k < 3000; ++k) {
      RigidState s = touching_state(m, rng, k % 3 == 0 ? 1000.0 : 20.0);
      const ContactSet c = touching_corners(m, s, 1e-6 * m.bounding_radius);
      ASSERT_EQ(c.n, 1);
      const Vec3 u0 = corner_velocity(m, s, c.vertex[0]);
      if (u0.z() >= 0.0) continue;
      const Vec3 v0 = s.velocity;
      apply_friction_impact(m, s, c, /*restitution=*/false);
      const Vec3 P = m.mass * (s.velocity - v0);
      const Vec3 u = corner_velocity(m, s, c.vertex[0]);
      const double scale = u0.norm();
      ++total;
      bool ok = std::abs(u.z()) <= 1e-9 * scale;
      const double pt = std::hypot(P.x(), P.y()), slip = std::hypot(u.x(), u.y());
      if (slip > 1e-7 * scale) {
        ++sliding;
        ok = ok && std::abs(pt - mu * P.z()) <= 1e-9 * mu * P.z();
        ok = ok && std::abs((P.x() * u.x() + P.y() * u.y()) / (pt * slip) + 1.0) <= 1e-7;
      } else {
        ok = ok && pt <= mu * P.z() * (1.0 + 1e-9);
      }
      if (!ok) ++broken;
    }
  }
  EXPECT_GT(sliding, total / 4);  // the sliding branch is really exercised
  EXPECT_LE(broken, total / 1000) << broken << " of " << total << " impacts break Coulomb's law";
}

TEST(FrictionImpact, FaceFirstLandingIsASymmetricFourPointImpact) {
  const DieModel m = compile(fair_scene());
  RigidState s;
  s.R = Mat3::Identity();
  s.position = Vec3(0, 0, 0.015);
  s.velocity = Vec3(0, 0, -2.0);
  const ContactSet c = touching_corners(m, s, 1e-6 * m.bounding_radius);
  ASSERT_EQ(c.n, 4);
  apply_friction_impact(m, s, c, true);
  EXPECT_NEAR(s.velocity.z(), 0.5 * 2.0, 1e-9);  // restitution 0.5, all four corners alike
  // Gauss-Seidel converges to 1e-11 of the speeds involved (2 m/s): no sideways motion or spin
  // beyond that.
  EXPECT_NEAR(s.velocity.x(), 0.0, 1e-10);
  EXPECT_NEAR(s.omega.norm() * m.bounding_radius, 0.0, 1e-10);
}

TEST(Friction, SlidingDieDeceleratesAtMuG) {
  for (double mu : {0.1, 0.3, 0.6}) {
    SceneDef def = fair_scene();
    def.materials["plastic"].friction = mu;
    const DieModel m = compile(def);
    RigidState s;
    s.R = Mat3::Identity();
    s.position = Vec3(0, 0, 0.015);
    s.velocity = Vec3(1.0, 0.0, 0.0);
    const double h = 1e-4;
    FixedStepper st(m, h);
    st.step(s);  // settle the contact
    const double v0 = s.velocity.x();
    const int n = 1000;  // 0.1 s, still sliding (needs 1 / (mu g) > 0.3 s)
    for (int k = 0; k < n; ++k) st.step(s);
    const double decel = (v0 - s.velocity.x()) / (n * h);
    // Each step removes exactly mu g h once the contact solve has converged (1e-14 relative):
    // the only error left is rounding.
    EXPECT_NEAR(decel, mu * m.gravity, 1e-6 * mu * m.gravity) << "mu " << mu;
    EXPECT_NEAR(s.position.z(), 0.015, 1e-9);   // stays on its face: no tipping below mu = 1
    EXPECT_NEAR(s.velocity.y(), 0.0, 1e-12);
  }
}

// Extremes for every fidelity (PHYSICS.md invariants, issue 3 item 3): no crash, no hang, no NaN,
// every toss accounted for; `unresolved` where the physics never settles; no impact gains energy.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "fidelity_test_util.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"

using namespace dicesim;
using namespace dicesim::testing;

namespace {

struct Extreme {
  std::string name;
  std::function<SceneDef()> make;
};

SceneDef with_materials(SceneDef s, double e, double mu) {
  for (auto& [n, mat] : s.materials) {
    mat.restitution = e;
    mat.friction = mu;
  }
  return s;
}

std::vector<Extreme> extremes() {
  return {
      {"restitution 0", [] { return with_materials(slab_scene(), 0.0, 0.3); }},
      {"restitution 1", [] { return with_materials(slab_scene(), 1.0, 0.3); }},
      {"friction 0", [] { return with_materials(slab_scene(), 0.5, 0.0); }},
      {"friction 2", [] { return with_materials(slab_scene(), 0.5, 2.0); }},
      {"spin 1000 rad/s",
       [] {
         SceneDef s = slab_scene();
         s.throw_.spin.kind = SpinKind::RandomAxis;
         s.throw_.spin.magnitude = {1000.0, 0.0};
         return s;
       }},
      {"drop height 0 on a face", [] { return at_rest(slab_scene(0.3), Vec3(0, 0, 0)); }},
      {"drop height 0 on an edge", [] { return at_rest(slab_scene(0.3), Vec3(0, 45, 0)); }},
      {"drop height 0 on a vertex", [] { return at_rest(slab_scene(0.3), Vec3(45, 54.7356103172, 0)); }},
      {"density ratio 1", [] { return slab_scene(0.5, 2714.3, 2714.3); }},
      {"density ratio 1e4", [] { return slab_scene(0.5, 2714.3e4, 2714.3); }},
      {"aluminium fraction 0", [] { return slab_scene(0.0); }},
      {"aluminium fraction 1", [] { return slab_scene(1.0); }},
      {"face first straight down",
       [] {
         SceneDef s = at_rest(fair_scene(), Vec3::Zero());
         s.throw_.height.mean += 0.5;
         s.throw_.velocity.mean = Vec3(0, 0, -3.0);
         return s;
       }},
      {"1 mm die",
       [] {
         SceneDef s = fair_scene(0.001);
         s.throw_.height = {0.05, 0.01};
         return s;
       }},
      {"1 m die",
       [] {
         SceneDef s = fair_scene(1.0);
         s.throw_.height = {2.0, 0.2};
         return s;
       }},
  };
}

}  // namespace

TEST(Extremes, EveryFidelityEndsEveryTossWithoutNaN) {
  for (Fidelity f : {Fidelity::Static, Fidelity::Paper, Fidelity::Impulse, Fidelity::Stepped}) {
    for (const Extreme& x : extremes()) {
      SceneDef def = with_fidelity(x.make(), f);
      def.sim.step = 1e-3;  // stepped: coarse here (no-crash test); accuracy is measured elsewhere
      def.sim.max_time = 5.0;
      const DieModel m = compile(def);
      const int n = f == Fidelity::Stepped ? 8 : 60;
      for (int i = 0; i < n; ++i) {
        std::vector<BounceRecord> trace;
        TossProbe probe;
        probe.trace = &trace;
        const TossResult r = toss(m, 17, static_cast<std::uint64_t>(i), &probe);
        ASSERT_NE(r.status, TossStatus::Invalid) << to_string(f) << ", " << x.name;
        ASSERT_TRUE(std::isfinite(r.t_end)) << to_string(f) << ", " << x.name;
        ASSERT_LE(r.t_end, def.sim.max_time + 1.0);
        if (r.status == TossStatus::Settled) {
          ASSERT_GE(r.face_index, 0);
          ASSERT_LT(r.face_index, 6);
        }
        // Every impact and every fixed step of `impulse`'s sustained contact and of `stepped`:
        // the largest relative energy gain, kinetic across an impact, kinetic + m g z across a
        // step (the traces above hold only `impulse`'s flight impacts).
        EXPECT_LE(probe.max_energy_gain, 1e-12) << to_string(f) << ", " << x.name << ", toss " << i;
        if (f == Fidelity::Impulse || f == Fidelity::Stepped) {
          EXPECT_EQ(r.corrections.energy_clamps, 0u) << to_string(f) << ", " << x.name << ", toss " << i;
          EXPECT_EQ(r.corrections.overlap_fixes, 0u) << to_string(f) << ", " << x.name << ", toss " << i;
        }
        for (const BounceRecord& b : trace) {
          ASSERT_TRUE(b.after.velocity.allFinite() && b.after.omega.allFinite()) << x.name;
          EXPECT_LE(kinetic_energy(m, b.after), kinetic_energy(m, b.before) * (1.0 + 1e-12) + 1e-300)
              << to_string(f) << ", " << x.name << ", impact " << b.bounce;
        }
      }
    }
  }
}

// Restitution 1 without friction conserves energy at every impact: the die never comes to rest,
// and that must be an answer (unresolved at the cap), not a hang.
TEST(Extremes, ElasticFrictionlessNeverSettles) {
  for (Fidelity f : {Fidelity::Impulse, Fidelity::Stepped}) {
    SceneDef def = with_fidelity(with_materials(slab_scene(), 1.0, 0.0), f);
    def.sim.step = 1e-3;
    def.sim.max_time = 3.0;
    const RunCounts r = run(compile(def), f == Fidelity::Stepped ? 6 : 40, 2);
    EXPECT_EQ(r.settled, 0u) << to_string(f);
    EXPECT_EQ(r.unresolved, r.total()) << to_string(f);
  }
}

// Thrown straight down face-first: a simultaneous four-point impact; the die bounces straight up
// and comes to rest on the face it landed on (-z down, +z = label 1 up).
TEST(Extremes, FaceFirstLandsAndStaysOnThatFace) {
  SceneDef s = at_rest(fair_scene(), Vec3::Zero());
  s.throw_.height.mean += 0.5;
  s.throw_.velocity.mean = Vec3(0, 0, -3.0);
  for (Fidelity f : {Fidelity::Static, Fidelity::Paper, Fidelity::Impulse, Fidelity::Stepped}) {
    SceneDef def = with_fidelity(s, f);
    def.sim.step = 1e-4;
    const TossResult r = toss(compile(def), 1, 0);
    EXPECT_EQ(r.status, TossStatus::Settled) << to_string(f);
    EXPECT_EQ(r.face, 1) << to_string(f);
  }
}

// Helpers shared by the fidelity-ladder tests (test_fidelity_*, test_friction*, test_rest*, test_extremes*,
// test_cylinder).
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "scenes_for_tests.hpp"
#include "sim/body/die_model.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"
#include "sim/study/monte_carlo.hpp"

namespace dicesim::testing {

// Counts pinned by face index (+x, -x, +y, -y, +z, -z: as first recorded for the box), in the
// label order RunCounts uses.
inline std::vector<std::uint64_t> in_label_order(const DieModel& m, const std::array<std::uint64_t, 6>& by_face) {
  std::vector<std::uint64_t> out(static_cast<std::size_t>(m.outcomes()), 0);
  for (std::size_t f = 0; f < 6; ++f) out[static_cast<std::size_t>(m.face_outcome[f])] += by_face[f];
  return out;
}

inline SceneDef with_fidelity(SceneDef s, Fidelity f) {
  s.sim.fidelity = f;
  return s;
}

// A die released at rest in a fixed orientation (z-x-z Euler degrees) with its lowest corner on
// the floor (drop height 0).
inline SceneDef at_rest(SceneDef s, const Vec3& euler_deg) {
  s.throw_.orientation.kind = OrientationKind::Fixed;
  s.throw_.orientation.euler_deg = euler_deg;
  s.throw_.velocity = {Vec3::Zero(), Vec3::Zero()};
  s.throw_.spin.kind = SpinKind::Normal;
  s.throw_.spin.components = {Vec3::Zero(), Vec3::Zero()};
  const DieModel probe = compile(s);
  const Vec3 e = euler_deg * (kPi / 180.0);
  const Mat3 R = euler_zxz(e.x(), e.y(), e.z()) * probe.geo_to_body.transpose();
  double depth = 0.0;
  for (const Vec3& v : probe.vertices) depth = std::max(depth, -(R * v).z());
  s.throw_.height = {depth, 0.0};
  return s;
}

// Toss `index` of a run with `seed`, leaving its final state in `end` (where it settled).
inline TossResult toss_to_end(const DieModel& m, std::uint64_t seed, std::uint64_t index, RigidState& end) {
  TossProbe probe;
  probe.final_state = &end;
  return toss(m, seed, index, &probe);
}

inline RunCounts run(const DieModel& m, std::uint64_t n, std::uint64_t seed = 1, int threads = 2) {
  RunConfig cfg;
  cfg.seed = seed;
  cfg.tosses = n;
  cfg.threads = threads;
  return run_tosses(m, cfg);
}

// A pinned run of one ready scene (test_paper_regression.cpp, test_impulse_regression.cpp).
struct Golden {
  const char* scene;
  std::array<std::uint64_t, 6> faces;  // by face index: +x, -x, +y, -y, +z, -z
  std::uint64_t bounces;
  // energy clamps, unconverged contact solves, overlap fixes, fallbacks: pinned too (the target
  // is 0; what they are today is recorded so that a change is seen).
  std::array<std::uint64_t, 4> corrections{};
};

// Runs g.scene in fidelity f, n tosses, seed 20261122 on 2 threads, and checks every pinned
// number; on a failure prints the actual values as a Golden line (how the pins are regenerated).
inline void check_pinned(const Golden& g, Fidelity f, std::uint64_t n) {
  const DieModel m = compile(with_fidelity(load_scene(std::string(DICESIM_SOURCE_DIR) + "/" + g.scene), f));
  const RunCounts c = run(m, n, 20261122);
  const std::string what = std::string(to_string(f)) + " " + g.scene;
  EXPECT_EQ(c.faces, in_label_order(m, g.faces)) << what;
  EXPECT_EQ(c.bounces, g.bounces) << what;
  EXPECT_EQ(c.settled, n) << what;
  const std::array<std::uint64_t, 4> corr = {c.corrections.energy_clamps, c.corrections.pgs_unconverged,
                                             c.corrections.overlap_fixes, c.corrections.fallbacks};
  EXPECT_EQ(corr, g.corrections) << what;
  EXPECT_EQ(c.corrections.energy_clamps, 0u) << what;  // the impact law's promise
  if (::testing::Test::HasFailure()) {  // the actual values, by face index as pinned
    std::array<std::uint64_t, 6> bf{};
    for (std::size_t k = 0; k < 6; ++k) bf[k] = c.faces[static_cast<std::size_t>(m.face_outcome[k])];
    std::printf("      {\"%s\", {%llu, %llu, %llu, %llu, %llu, %llu}, %llu, {%llu, %llu, %llu, %llu}},\n", g.scene,
                (unsigned long long)bf[0], (unsigned long long)bf[1], (unsigned long long)bf[2],
                (unsigned long long)bf[3], (unsigned long long)bf[4], (unsigned long long)bf[5],
                (unsigned long long)c.bounces, (unsigned long long)corr[0], (unsigned long long)corr[1],
                (unsigned long long)corr[2], (unsigned long long)corr[3]);
  }
}

// Above every basin's barrier: the energy criterion cannot decide (only lying flat can).
inline bool above_barriers(const DieModel& m, const RigidState& s) {
  const Vec3 wb = s.R.transpose() * s.omega;
  const double ke = 0.5 * m.mass * s.velocity.squaredNorm() + 0.5 * wb.dot(m.principal_moments.cwiseProduct(wb));
  return ke + m.mass * m.gravity * s.position.z() >= m.mass * m.gravity * m.max_escape;
}

// Soundness of a rest rule: for tosses [0, n) at `seed`, from every settled toss's final state the
// rule names the face the toss read, and `steps` more contact steps of length h never change the
// face down that down_face(m, R) reads every `every` steps (the energy was below the basin's saddle,
// or the die lay flat, and stays so). Returns how many tosses settled and how many of those ended
// above every basin's barrier (only the lying-flat rule can decide those).
struct RestSoundness {
  int settled = 0, above_barriers = 0;
};
template <class DownFace>
RestSoundness check_rest_is_sound(const DieModel& m, std::uint64_t seed, int n, double h, int steps, int every,
                                  DownFace down_face, const std::string& what) {
  RestSoundness out;
  for (int i = 0; i < n; ++i) {
    RigidState s;
    const TossResult r = toss_to_end(m, seed, static_cast<std::uint64_t>(i), s);
    if (r.status != TossStatus::Settled) continue;
    ++out.settled;
    const int down = rest_face_down(m, s, 0.5);
    if (down < 0 || result_face(m, down) != r.face_index) {
      ADD_FAILURE() << what << " toss " << i << ": the rest rule names face " << down << " for a toss read as "
                    << r.face_index;
      return out;
    }
    out.above_barriers += above_barriers(m, s);
    FixedStepper st(m, h);
    for (int k = 1; k <= steps; ++k) {
      st.step(s);
      if (k % every == 0 && down_face(m, s.R) != down) {
        ADD_FAILURE() << what << " toss " << i << ": face " << down << " left at step " << k;
        return out;
      }
    }
  }
  return out;
}

}  // namespace dicesim::testing

// Helpers shared by the fidelity-ladder tests (test_fidelity_*, test_friction*, test_rest*, test_extremes*).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "scenes_for_tests.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"
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

inline RunCounts run(const DieModel& m, std::uint64_t n, std::uint64_t seed = 1, int threads = 2) {
  RunConfig cfg;
  cfg.seed = seed;
  cfg.tosses = n;
  cfg.threads = threads;
  return run_tosses(m, cfg);
}

}  // namespace dicesim::testing

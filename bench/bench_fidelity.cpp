// Micro-benchmarks of the fidelity ladder on the seed's Die 1 (friction 0.3 assumed): one toss per
// fidelity, the friction impact law, one fixed step. The speed/accuracy table: `dicesim bench tradeoff`.
#include <benchmark/benchmark.h>

#include <vector>

#include "sim/dynamics/contact_stepper.hpp"
#include "sim/body/die_model.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/initial_state.hpp"
#include "sim/models/toss_random.hpp"
#include "sim/models/toss.hpp"

namespace {

using namespace dicesim;

DieModel die1_as(Fidelity f) {
  return compile(load_scene(DICESIM_SOURCE_DIR "/scenes/paper/die1.toml", {std::string("sim.fidelity=") + to_string(f)}));
}

void toss_bench(benchmark::State& st, Fidelity f) {
  const DieModel m = die1_as(f);
  std::uint64_t i = 0;
  for (auto _ : st) benchmark::DoNotOptimize(toss(m, 1, i++));
  st.SetItemsProcessed(static_cast<int64_t>(i));
}
void BM_TossStatic(benchmark::State& st) { toss_bench(st, Fidelity::Static); }
void BM_TossImpulse(benchmark::State& st) { toss_bench(st, Fidelity::Impulse); }
void BM_TossStepped(benchmark::State& st) { toss_bench(st, Fidelity::Stepped); }
BENCHMARK(BM_TossStatic);
BENCHMARK(BM_TossImpulse);
BENCHMARK(BM_TossStepped)->Unit(benchmark::kMillisecond);

// One corner strikes: the Chatterjee-Ruina law with the energy guard.
void BM_FrictionImpactOneCorner(benchmark::State& st) {
  const DieModel m = die1_as(Fidelity::Impulse);
  RigidState s0;
  s0.R = Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  double low = 0.0;
  for (const Vec3& v : m.vertices) low = std::min(low, (s0.R * v).z());
  s0.position = Vec3(0, 0, -low);
  s0.velocity = Vec3(0.5, 0.2, -2.0);
  s0.omega = Vec3(10, -5, 3);
  const ContactSet c = touching_corners(m, s0, 1e-6 * m.bounding_radius);
  for (auto _ : st) {
    RigidState s = s0;
    benchmark::DoNotOptimize(apply_friction_impact(m, s, c, true));
  }
}
BENCHMARK(BM_FrictionImpactOneCorner);

// The common case of sustained contact: one corner, perfectly plastic, mostly sliding. A fixed
// set of 64 random approaching single-corner states (spin ~20 rad/s) cycled, so the mix includes
// the strongly coupled states where the angle root-finder decides the slip direction.
void BM_FrictionImpactPlasticCornerMix(benchmark::State& st) {
  const DieModel m = die1_as(Fidelity::Impulse);
  std::vector<RigidState> states;
  TossRandom rng(14, 0);
  while (states.size() < 64) {
    RigidState s;
    s.R = uniform_rotation(rng.uniform(), rng.uniform(), rng.uniform());
    double low = 0.0;
    for (const Vec3& v : m.vertices) low = std::min(low, (s.R * v).z());
    s.position = Vec3(0, 0, -low);
    s.velocity = Vec3(rng.normal(), rng.normal(), -3.0 * rng.uniform());
    s.omega = 20.0 * Vec3(rng.normal(), rng.normal(), rng.normal());
    const ContactSet c = touching_corners(m, s, 1e-6 * m.bounding_radius);
    if (c.n == 1 && corner_velocity(m, s, c.vertex[0]).z() < 0.0) states.push_back(s);
  }
  std::size_t i = 0;
  for (auto _ : st) {
    RigidState s = states[i++ % states.size()];
    benchmark::DoNotOptimize(apply_friction_impact(m, s, touching_corners(m, s, 1e-6 * m.bounding_radius), false));
  }
}
BENCHMARK(BM_FrictionImpactPlasticCornerMix);

// A die resting on a face: one step of the sustained-contact integrator (four corners).
void BM_FixedStepOnFace(benchmark::State& st) {
  const DieModel m = die1_as(Fidelity::Stepped);
  RigidState s;
  s.R = m.geo_to_body.transpose();
  double low = 0.0;
  for (const Vec3& v : m.vertices) low = std::min(low, (s.R * v).z());
  s.position = Vec3(0, 0, -low);
  FixedStepper stepper(m, 2e-4);
  for (auto _ : st) benchmark::DoNotOptimize(stepper.step(s));
}
BENCHMARK(BM_FixedStepOnFace);

}  // namespace

// Micro-benchmarks of the `paper` fidelity's stages on the seed's Die 1 (seed-like throws:
// COM 1 m, spin sd 18 rad/s). End-to-end throughput per thread and scaling: `dicesim bench`.
#include <benchmark/benchmark.h>

#include "sim/dynamics/contact.hpp"
#include "sim/body/die_model.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/models/toss.hpp"

namespace {

using namespace dicesim;

const DieModel& die1() {
  static const DieModel m = compile(load_scene(DICESIM_SOURCE_DIR "/scenes/paper/die1.toml"));
  return m;
}

void BM_Toss(benchmark::State& st) {
  const DieModel& m = die1();
  std::uint64_t i = 0;
  for (auto _ : st) benchmark::DoNotOptimize(toss(m, 1, i++));
  st.SetItemsProcessed(static_cast<int64_t>(i));
}
BENCHMARK(BM_Toss);

void BM_DrawInitialState(benchmark::State& st) {
  const DieModel& m = die1();
  std::uint64_t i = 0;
  for (auto _ : st) benchmark::DoNotOptimize(draw_initial_state(m.throw_, 1, i++));
  st.SetItemsProcessed(static_cast<int64_t>(i));
}
BENCHMARK(BM_DrawInitialState);

void BM_FirstContactSearch(benchmark::State& st) {
  const DieModel& m = die1();
  std::vector<RigidState> starts;
  for (std::uint64_t i = 0; i < 1024; ++i) starts.push_back(to_body_state(m, draw_initial_state(m.throw_, 1, i)));
  std::size_t k = 0;
  for (auto _ : st) {
    const Flight f(m, starts[k++ & 1023]);
    benchmark::DoNotOptimize(f.next_contact(60.0));
  }
  st.SetItemsProcessed(static_cast<int64_t>(k));
}
BENCHMARK(BM_FirstContactSearch);

void BM_Impact(benchmark::State& st) {
  const DieModel& m = die1();
  RigidState s;
  s.R = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  s.velocity = Vec3(0.1, 0.2, -4.0);
  s.omega = Vec3(10, -5, 3);
  for (auto _ : st) {
    RigidState x = s;
    benchmark::DoNotOptimize(apply_vertex_impact(m, x, 0));
    benchmark::DoNotOptimize(x);
  }
}
BENCHMARK(BM_Impact);

void BM_RunTosses(benchmark::State& st) {
  const DieModel& m = die1();
  RunConfig cfg;
  cfg.tosses = 100000;
  cfg.threads = static_cast<int>(st.range(0));
  for (auto _ : st) benchmark::DoNotOptimize(run_tosses(m, cfg));
  st.SetItemsProcessed(static_cast<int64_t>(st.iterations() * cfg.tosses));
}
BENCHMARK(BM_RunTosses)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

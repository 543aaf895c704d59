// `dicesim show`'s toss data (web/show_data.hpp): sustained contact is the stepper's recorded
// states, not an interpolation, and watching the steps changes no toss.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fidelity_test_util.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"
#include "sim/scene/scene.hpp"
#include "web/show_data.hpp"

namespace {

using namespace dicesim;

DieModel model(const std::string& scene, Fidelity f) {
  return compile(dicesim::testing::with_fidelity(load_scene(std::string(DICESIM_SOURCE_DIR) + "/" + scene), f));
}

// Every state the stepper reports.
struct AllSteps final : StepObserver {
  std::vector<std::pair<double, RigidState>> states;
  void on_step(double t, const RigidState& s) override { states.emplace_back(t, s); }
};

// Toss `index` with and without an observer: the same toss, bit for bit; the steps seen.
AllSteps watched(const DieModel& m, std::uint64_t index) {
  AllSteps all;
  TossProbe probe;
  probe.steps_observer = &all;
  const TossResult a = toss(m, 5, index, &probe);
  const TossResult b = toss(m, 5, index);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.face, b.face);
  EXPECT_EQ(a.bounces, b.bounces);
  EXPECT_EQ(a.t_end, b.t_end);  // exact: the observer reads, never changes
  EXPECT_EQ(a.corrections.energy_clamps, b.corrections.energy_clamps);
  return all;
}

// The toss's frames in sustained contact are states the stepper went through (to the page's 7
// digits), and no stretch is interpolated.
void expect_recorded(const DieModel& m, std::uint64_t index) {
  const AllSteps all = watched(m, index);
  const nlohmann::json t = web::toss_json(m, 5, index);
  const std::string what = std::string(to_string(m.fidelity)) + " toss " + std::to_string(index);
  EXPECT_EQ(t["interpolated"].size(), 0u) << what << ": " << t["interpolated"].dump();
  ASSERT_FALSE(all.states.empty()) << what << " took no fixed step: pick another toss";
  EXPECT_GT(t["steps_recorded"].get<std::size_t>(), 0u) << what;
  // Each recorded step's frame is found among the stepper's states at its time.
  std::size_t matched = 0;
  const double r = m.bounding_radius;  // 12.6 mm for the d20
  for (const auto& f : t["frames"]) {
    const double time = f[0].get<double>();
    const Vec3 p(f[1].get<double>(), f[2].get<double>(), f[3].get<double>());
    auto it = std::lower_bound(all.states.begin(), all.states.end(), time - 2e-6,
                               [](const auto& e, double x) { return e.first < x; });
    for (; it != all.states.end() && it->first <= time + 2e-6; ++it)
      if ((p - it->second.position).norm() <= 1e-6 * p.norm() + 1e-6 * r) {  // the page's 7 digits
        ++matched;
        break;
      }
  }
  EXPECT_GE(matched, t["steps_recorded"].get<std::size_t>()) << what;
  // The stepper's phase spans the frames: between its first and last state, no frame gap is longer
  // than 1 ms or one step (recorded, then drawn between neighbours).
  const double t0 = all.states.front().first, t1 = all.states.back().first;
  const double bound = std::max(1e-3, std::max(m.contact_step, m.step)) + 2e-6;
  double prev = -1.0;
  for (const auto& f : t["frames"]) {
    const double time = f[0].get<double>();
    if (prev >= t0 && time <= t1) {
      EXPECT_LE(time - prev, bound) << what << " at t = " << time;
    }
    prev = time;
  }
}

TEST(ShowData, SustainedContactOfImpulseIsTheStepsRecorded) {
  const DieModel m = model("scenes/dice/d20.toml", Fidelity::Impulse);
  for (const std::uint64_t i : {7u, 19000u}) expect_recorded(m, i);
}

TEST(ShowData, SteppedTossIsTheStepsRecorded) {
  expect_recorded(model("scenes/paper/die1.toml", Fidelity::Stepped), 3);
}

TEST(ShowData, WatchingTheStepsChangesNoToss) {
  const DieModel m = model("scenes/paper/die1.toml", Fidelity::Impulse);
  std::size_t steps = 0;
  for (std::uint64_t i = 0; i < 200; ++i) steps += watched(m, i).states.size();
  EXPECT_GT(steps, 0u);
}

}  // namespace

// How tosses reach their outcome (issue 40's censuses), from StepObserver and the impact trace:
//   dicesim_census edge SCENE    a cylinder: how each `edge` landing arrived, and how fast the coin
//                                still moved when its energy fell below the side's barrier
//   dicesim_census basins SCENE  any die: the basins (quasi-static down face) a toss visits, and the
//                                energy with which it entered the one it ends in
//   dicesim_census spun SCENE    a cylinder stood on its side, tilted --tilt degrees, spun about the
//                                vertical at each --spin: the face it ends on and when
// The tosses are the scene's own (seed, index); --per-toss FILE writes one line per toss.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "sim/body/rim.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/dynamics/rim_rest.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"
#include "sim/scene/scene.hpp"

using namespace dicesim;

namespace {

enum Via { kStep = 0, kFlight = 1, kImpact = 2 };  // how a state was reached
const char* kViaName[3] = {"a fixed step (in contact)", "in flight", "at an impact"};

// Held energy in lift units (m): kinetic / (m g) + COM height + depth of the lowest point.
double lift_energy(const DieModel& m, const RigidState& s) {
  double low = 1e300;
  for (int i = 0; i < m.vertex_count(); ++i) low = std::min(low, contact_point(m, s.R, i).z());
  return kinetic_energy(m, s) / (m.mass * m.gravity) + s.position.z() + std::max(0.0, -(s.position.z() + low));
}

double rotational_lift(const DieModel& m, const RigidState& s) {
  const Vec3 wb = s.R.transpose() * s.omega;
  return 0.5 * wb.dot(m.principal_moments.cwiseProduct(wb)) / (m.mass * m.gravity);
}

std::string pct(std::vector<double> v, double scale = 1.0, int digits = 2) {
  if (v.empty()) return "-";
  std::sort(v.begin(), v.end());
  std::string out;
  for (double q : {0.1, 0.5, 0.9}) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "%s%.*f", out.empty() ? "" : " / ", digits, scale * v[static_cast<std::size_t>(q * (v.size() - 1))]);
    out += buf;
  }
  return out;
}

// Feeds every state of a toss (impacts from the trace, fixed steps from the observer) to f.
template <class F>
struct Feed : StepObserver {
  std::vector<BounceRecord> trace;
  std::size_t seen = 0;
  F f;
  explicit Feed(F fn) : f(fn) {}
  void drain() {
    for (; seen < trace.size(); ++seen) {
      f(trace[seen].t, trace[seen].before, kFlight);
      f(trace[seen].t, trace[seen].after, kImpact);
    }
  }
  void on_step(double t, const RigidState& s) override {
    drain();
    f(t, s, kStep);
  }
};

template <class F>
TossResult run_toss(const DieModel& m, std::uint64_t seed, std::uint64_t i, F f) {
  Feed<F> feed(f);
  RigidState fin;
  TossProbe probe;
  probe.trace = &feed.trace;
  probe.steps_observer = &feed;
  probe.final_state = &fin;
  const TossResult r = toss(m, seed, i, &probe);
  feed.drain();
  feed.f(r.t_end, fin, kStep);
  return r;
}

// --- edge ------------------------------------------------------------------------------------

struct Snap {
  double t = 0, excess = 0, vh = 0, w_roll = 0, w_z = 0;
  int via = kStep;
};

int census_edge(const DieModel& m, std::uint64_t seed, std::uint64_t first, std::uint64_t n, std::FILE* per) {
  if (!m.curved()) {
    std::fprintf(stderr, "dicesim_census edge: the scene's die is not a cylinder\n");
    return 2;
  }
  const double barrier = m.face_escape[2] - m.face_height[2];
  std::uint64_t settled = 0, edges = 0;
  std::map<std::string, int> arrivals;
  int moving_below = 0;
  std::vector<double> w_in, roll_in, w_below, upright_s, stop_s, excess_in;
  for (std::uint64_t i = first; i < first + n; ++i) {
    bool in = false, have_below = false;
    Snap entry, below;
    double t_last = 0;
    const TossResult r = run_toss(m, seed, i, [&](double t, const RigidState& s, int via) {
      const bool side = rim_quasi_static_down(m, s.R, 0.5) == 2;
      t_last = t;
      if (!side) {
        in = false;
        return;
      }
      const double excess = lift_energy(m, s) - m.face_escape[2];
      const Vec3 K = s.R * m.rims.axis;
      const Snap now{t, excess, std::hypot(s.velocity.x(), s.velocity.y()), s.omega.dot(K), s.omega.z(), via};
      if (!in) {
        in = true;
        have_below = false;
        entry = now;
      }
      if (!have_below && excess < 0.0) {
        below = now;
        have_below = true;
      }
    });
    if (r.status != TossStatus::Settled) continue;
    ++settled;
    if (per) std::fprintf(per, "%llu %d %.4f %d", (unsigned long long)i, r.face_index, r.t_end, r.bounces);
    if (r.face_index == 2) {
      ++edges;
      // A thin disc's moments: rolling (with the COM's motion) 3/4 m a^2 w^2, spinning about a
      // diameter 1/8 m a^2 w^2: which motion held more energy on entering the side's basin.
      const double roll_e = 6.0 * entry.w_roll * entry.w_roll, spin_e = entry.w_z * entry.w_z;
      const std::string how = entry.via != kStep ? "bounced onto it (entered " + std::string(kViaName[entry.via]) + ")"
                              : spin_e >= roll_e ? "spun upright (entered spinning about the vertical)"
                                                 : "landed on the rim and rolled";
      ++arrivals[how];
      w_in.push_back(std::abs(entry.w_z));
      roll_in.push_back(std::abs(entry.w_roll));
      excess_in.push_back(entry.excess);
      upright_s.push_back(t_last - entry.t);
      if (have_below) {
        const bool moving = std::abs(below.w_z) > 1.0 || std::abs(below.w_roll) > 1.0 || below.vh > 5e-3;
        moving_below += moving;
        w_below.push_back(std::abs(below.w_z));
        stop_s.push_back(t_last - below.t);
      }
      if (per)
        std::fprintf(per, " entry %d %.4f %.6f %.4f %.4f %.4f", entry.via, entry.t, entry.excess, entry.vh, entry.w_roll,
                     entry.w_z);
    }
    if (per) std::fprintf(per, "\n");
  }
  std::printf("edge census: tosses %llu..%llu, seed %llu, contact_step %g s; side barrier %.1f um of lift\n",
              (unsigned long long)first, (unsigned long long)(first + n - 1), (unsigned long long)seed, m.contact_step,
              barrier * 1e6);
  std::printf("settled %llu, edge %llu (1 in %.0f)\n", (unsigned long long)settled, (unsigned long long)edges,
              edges ? double(settled) / double(edges) : 0.0);
  for (const auto& [how, k] : arrivals) std::printf("  %5d  %s\n", k, how.c_str());
  std::printf("on entering the side's basin (last time): |w_z| %s rad/s, |w_roll| %s rad/s, energy above the barrier %s mm\n",
              pct(w_in).c_str(), pct(roll_in).c_str(), pct(excess_in, 1e3).c_str());
  std::printf("below the barrier while still moving (|w| > 1 rad/s or v > 5 mm/s): %d of %llu; |w_z| then %s rad/s\n",
              moving_below, (unsigned long long)edges, pct(w_below).c_str());
  std::printf("on the side before the end: %s s; from below the barrier to the end: %s s  (10th / 50th / 90th percentiles)\n",
              pct(upright_s).c_str(), pct(stop_s, 1.0, 3).c_str());
  return 0;
}

// --- basins ----------------------------------------------------------------------------------

int census_basins(const DieModel& m, std::uint64_t seed, std::uint64_t first, std::uint64_t n,
                  const std::vector<int>& group, std::FILE* per) {
  auto in_group = [&](int face) { return std::find(group.begin(), group.end(), m.face_labels[face]) != group.end(); };
  const double unit = m.max_escape;  // energies in multiples of the highest saddle
  const double bins[] = {0.0, 1.0, 2.0, 4.0, 8.0, 1e300};
  int bin_n[5] = {}, bin_g[5] = {};
  int via_n[3] = {}, via_g[3] = {};
  std::uint64_t settled = 0, in_g = 0;
  std::vector<double> e_g, e_o, rot_g, rot_o, visits;
  for (std::uint64_t i = first; i < first + n; ++i) {
    int basin = -2, changes = 0;
    double e_entry = 0, rot_entry = 0;
    int via_entry = kStep;
    const TossResult r = run_toss(m, seed, i, [&](double, const RigidState& s, int via) {
      const int b = m.curved() ? rim_quasi_static_down(m, s.R, 0.5) : quasi_static_down_face(m, s.R, 0.5);
      if (b == basin) return;
      basin = b;
      ++changes;
      e_entry = lift_energy(m, s);
      rot_entry = rotational_lift(m, s);
      via_entry = via;
    });
    if (r.status != TossStatus::Settled) continue;
    ++settled;
    const bool g = in_group(r.face_index);
    in_g += g;
    (g ? e_g : e_o).push_back(e_entry / unit);
    (g ? rot_g : rot_o).push_back(rot_entry / unit);
    visits.push_back(changes);
    ++via_n[via_entry];
    via_g[via_entry] += g;
    for (int k = 0; k < 5; ++k)
      if (e_entry / unit >= bins[k] && e_entry / unit < bins[k + 1]) {
        ++bin_n[k];
        bin_g[k] += g;
      }
    if (per)
      std::fprintf(per, "%llu %d %d %d %.6f %.6f\n", (unsigned long long)i, r.face_index, changes, via_entry, e_entry,
                   rot_entry);
  }
  std::printf("basin census: tosses %llu..%llu, seed %llu, contact_step %g s; energies in units of the highest saddle, %.3f mm of lift\n",
              (unsigned long long)first, (unsigned long long)(first + n - 1), (unsigned long long)seed, m.contact_step,
              unit * 1e3);
  std::printf("settled %llu; ending on the group's faces: %.4f\n", (unsigned long long)settled,
              settled ? double(in_g) / double(settled) : 0.0);
  std::printf("basins visited: %s\n", pct(visits, 1.0, 0).c_str());
  for (int k = 0; k < 3; ++k)
    std::printf("final basin entered %-26s %6d tosses, group share %.3f\n", kViaName[k], via_n[k],
                via_n[k] ? double(via_g[k]) / via_n[k] : 0.0);
  std::printf("energy on entering the final basin: group %s, others %s; of it rotational: group %s, others %s\n",
              pct(e_g).c_str(), pct(e_o).c_str(), pct(rot_g).c_str(), pct(rot_o).c_str());
  for (int k = 0; k < 5; ++k)
    if (bin_n[k])
      std::printf("  final entry at E in [%g, %g) saddles: %6d tosses, group share %.3f\n", bins[k],
                  k == 4 ? INFINITY : bins[k + 1], bin_n[k], double(bin_g[k]) / bin_n[k]);
  return 0;
}

// --- spun ------------------------------------------------------------------------------------

int census_spun(const DieModel& m, double tilt_deg, const std::vector<double>& spins) {
  if (!m.curved()) {
    std::fprintf(stderr, "dicesim_census spun: the scene's die is not a cylinder\n");
    return 2;
  }
  const char* names[3] = {"face 0 (heads) down", "face 1 (tails) down", "edge"};
  std::printf("spun upright: tilt %.2f deg from upright, no roll, contact_step %g s (impulse's sustained steps)\n", tilt_deg,
              m.contact_step);
  for (const double w : spins) {
    RigidState s;
    const double tilt = tilt_deg * kPi / 180.0;
    s.R = Quat::FromTwoVectors(m.rims.axis, Vec3(std::cos(tilt), 0.0, std::sin(tilt))).toRotationMatrix();
    s.position = Vec3(0.0, 0.0, -rim_lowest(m, s.R));
    s.omega = Vec3(0.0, 0.0, w);
    double t = 0.0;
    int impacts = 0;
    const StepperOutcome o =
        run_fixed_steps(m, s, t, impacts, m.contact_step, 0.3, /*allow_liftoff=*/true, ImpactThreshold::Gravity, nullptr);
    const char* end = o.exit == StepperExit::LiftOff ? "lifted off the table (not followed)"
                      : o.exit == StepperExit::Settled && o.face_down >= 0 ? names[o.face_down]
                                                                            : "unresolved";
    std::printf("  %6.1f rad/s: %s after %.2f s\n", w, end, t);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"How tosses reach their outcome: the censuses of issue 40 (per-toss detail with --per-toss)."};
  std::string kind, scene, per_toss;
  std::uint64_t seed = 1, first = 0, n = 10000;
  std::vector<std::string> overrides;
  std::vector<int> group;
  app.add_option("kind", kind, "edge (a cylinder's edge landings), basins (any die) or spun (a cylinder spun upright)")->required()->check(CLI::IsMember({"edge", "basins", "spun"}));
  app.add_option("scene", scene, "scene file")->required()->check(CLI::ExistingFile);
  app.add_option("--seed", seed, "run seed (default 1)");
  app.add_option("--first", first, "first toss index (default 0)");
  app.add_option("-n,--tosses", n, "tosses (default 10000)")->check(CLI::Range(1, 100000000));
  app.add_option("--set", overrides, "KEY=VALUE scene override (repeatable)");
  app.add_option("--group", group, "basins: face labels counted as one group (e.g. --group 9 10)");
  app.add_option("--per-toss", per_toss, "write one line per toss to FILE");
  double tilt = 1.3;
  std::vector<double> spins = {10, 20, 40, 60, 80, 100};
  app.add_option("--tilt", tilt, "spun: degrees from upright (default 1.3)")->check(CLI::Range(0.0, 30.0));
  app.add_option("--spin", spins, "spun: spins about the vertical, rad/s (default 10 20 40 60 80 100)");
  CLI11_PARSE(app, argc, argv);
  try {
    const DieModel m = compile(load_scene(scene, overrides));
    std::FILE* per = per_toss.empty() ? nullptr : std::fopen(per_toss.c_str(), "w");
    if (!per_toss.empty() && !per) {
      std::fprintf(stderr, "dicesim_census: cannot write %s\n", per_toss.c_str());
      return 2;
    }
    const int rc = kind == "edge"   ? census_edge(m, seed, first, n, per)
                   : kind == "spun" ? census_spun(m, tilt, spins)
                                    : census_basins(m, seed, first, n, group, per);
    if (per) std::fclose(per);
    return rc;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dicesim_census: %s\n", e.what());
    return 2;
  }
}

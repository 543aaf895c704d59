// Coverage of `dicesim fit`'s 95% intervals (docs/fitting.md): REPS repetitions, each with its own
// synthetic data (N tosses of SCENE at the true values, data seed 1000 + rep) and its own
// simulation seed (5000 + rep). Prints one CSV line per repetition and key, then per key the
// coverage with its Wilson interval and the mean interval width against the ideal (Fisher) width,
// and (several keys) how often every interval covered at once.
//   fit_coverage SCENE FIDELITY KEYS TRUTHS LOS HIS N REPS TOSSES [THREADS] [FIRST]
// KEYS, TRUTHS, LOS, HIS: comma-separated lists of one to three keys and their values.
// FIRST (default 0): the first repetition's index, so a long study can run in parts.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "sim/models/compile.hpp"
#include "sim/scene/scene.hpp"
#include "sim/study/fit.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/study/sweep.hpp"

using namespace dicesim;

namespace {

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) out.push_back(item);
  return out;
}

std::vector<double> numbers(const std::string& s) {
  std::vector<double> out;
  for (const std::string& item : split(s)) out.push_back(std::atof(item.c_str()));
  return out;
}

struct KeyTally {
  std::uint64_t covered = 0, covered_profile = 0, open = 0;
  double width = 0.0, ideal = 0.0, est = 0.0, mc = 0.0;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 10) {
    std::fprintf(stderr, "usage: fit_coverage SCENE FIDELITY KEYS TRUTHS LOS HIS N REPS TOSSES [THREADS] [FIRST]\n");
    return 2;
  }
  const std::string scene = argv[1], fidelity = argv[2];
  const std::vector<std::string> keys = split(argv[3]);
  const std::vector<double> truth = numbers(argv[4]), lo = numbers(argv[5]), hi = numbers(argv[6]);
  if (keys.empty() || keys.size() > 3 || truth.size() != keys.size() || lo.size() != keys.size() || hi.size() != keys.size()) {
    std::fprintf(stderr, "fit_coverage: KEYS, TRUTHS, LOS and HIS need one to three entries each, as many of each\n");
    return 2;
  }
  const auto n = std::strtoull(argv[7], nullptr, 10), reps = std::strtoull(argv[8], nullptr, 10),
             tosses = std::strtoull(argv[9], nullptr, 10);
  const int threads = argc > 10 ? std::atoi(argv[10]) : 2;
  const std::uint64_t first = argc > 11 ? std::strtoull(argv[11], nullptr, 10) : 0;
  const std::vector<std::string> fid{"sim.fidelity=\"" + fidelity + "\""};
  std::vector<std::string> at_truth = fid;
  std::vector<FitParam> params;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    at_truth.push_back(keys[i] + "=" + number_text(truth[i]));
    params.push_back({keys[i], lo[i], hi[i]});
  }
  const DieModel truth_model = compile(load_scene(scene, at_truth), scene);

  const auto t0 = std::chrono::steady_clock::now();
  std::vector<KeyTally> tally(keys.size());
  std::uint64_t all_covered = 0;
  std::printf("rep,key,estimate,lo,hi,profile_lo,profile_hi,mc_sd,fisher_halfwidth,covers\n");
  for (std::uint64_t rep = first; rep < first + reps; ++rep) {
    RunConfig cfg;
    cfg.seed = 1000 + rep;
    cfg.tosses = n;
    cfg.threads = threads;
    const RunCounts c = run_tosses(truth_model, cfg);
    FitOptions opt;
    opt.overrides = fid;
    opt.seed = 5000 + rep;
    opt.threads = threads;
    opt.tosses = tosses;
    const FitResult r = run_fit(params, {{scene, {}, "synthetic", {truth_model.outcome_labels, c.faces}}}, opt);
    bool all = true;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      const FitParamResult& p = r.params[i];
      KeyTally& t = tally[i];
      const bool cov = p.ci95.lo <= truth[i] && truth[i] <= p.ci95.hi;
      all = all && cov;
      t.covered += cov;
      t.covered_profile += p.ci95_profile.lo <= truth[i] && truth[i] <= p.ci95_profile.hi;
      t.open += p.lo_open || p.hi_open;
      t.width += p.ci95.hi - p.ci95.lo;
      t.ideal += 2.0 * p.fisher_halfwidth;
      t.est += p.estimate;
      t.mc += p.mc_sd;
      std::printf("%llu,%s,%.6g,%.6g,%.6g,%.6g,%.6g,%.4g,%.4g,%d\n", static_cast<unsigned long long>(rep), p.key.c_str(),
                  p.estimate, p.ci95.lo, p.ci95.hi, p.ci95_profile.lo, p.ci95_profile.hi, p.mc_sd, p.fisher_halfwidth,
                  cov ? 1 : 0);
    }
    all_covered += all;
    std::fflush(stdout);
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double R = static_cast<double>(reps);
  std::printf("# %s %s, N = %llu observed, %llu tosses per point (last round; 0: the fit's default), %llu repetitions\n",
              scene.c_str(), fidelity.c_str(), static_cast<unsigned long long>(n), static_cast<unsigned long long>(tosses),
              static_cast<unsigned long long>(reps));
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const KeyTally& t = tally[i];
    const Interval ci = wilson_interval(t.covered, reps);
    std::printf("# %s = %g in [%g, %g]: coverage %llu / %llu = %.3f, 95%% Wilson [%.3f, %.3f]; profile alone %llu; "
                "open intervals %llu\n",
                keys[i].c_str(), truth[i], lo[i], hi[i], static_cast<unsigned long long>(t.covered),
                static_cast<unsigned long long>(reps), static_cast<double>(t.covered) / R, ci.lo, ci.hi,
                static_cast<unsigned long long>(t.covered_profile), static_cast<unsigned long long>(t.open));
    std::printf("#   mean estimate %.6g; mean width %.4g, mean ideal (Fisher) width %.4g, ratio %.3f; mean MC sd %.4g\n",
                t.est / R, t.width / R, t.ideal / R, t.width / t.ideal, t.mc / R);
  }
  if (keys.size() > 1) {
    const Interval ci = wilson_interval(all_covered, reps);
    std::printf("# every interval at once: %llu / %llu = %.3f, 95%% Wilson [%.3f, %.3f] (intervals are per key, not joint)\n",
                static_cast<unsigned long long>(all_covered), static_cast<unsigned long long>(reps),
                static_cast<double>(all_covered) / R, ci.lo, ci.hi);
  }
  std::printf("# %.1f s, %.2f s per fit\n", s, s / R);
  return 0;
}

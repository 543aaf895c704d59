// Coverage of `dicesim fit`'s 95% intervals (docs/fitting.md): REPS repetitions, each with its own
// synthetic data (N tosses of SCENE at KEY = TRUTH, data seed 1000 + rep) and its own simulation
// seed (5000 + rep). Prints one CSV line per repetition, then the coverage with its Wilson interval
// and the mean interval width against the ideal (Fisher) width.
//   fit_coverage SCENE FIDELITY KEY TRUTH LO HI N REPS TOSSES [THREADS] [FIRST]
// FIRST (default 0): the first repetition's index, so a long study can run in parts.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "sim/models/compile.hpp"
#include "sim/scene/scene.hpp"
#include "sim/study/fit.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/study/sweep.hpp"

using namespace dicesim;

int main(int argc, char** argv) {
  if (argc < 10) {
    std::fprintf(stderr, "usage: fit_coverage SCENE FIDELITY KEY TRUTH LO HI N REPS TOSSES [THREADS] [FIRST]\n");
    return 2;
  }
  const std::string scene = argv[1], fidelity = argv[2], key = argv[3];
  const double truth = std::atof(argv[4]), lo = std::atof(argv[5]), hi = std::atof(argv[6]);
  const auto n = std::strtoull(argv[7], nullptr, 10), reps = std::strtoull(argv[8], nullptr, 10),
             tosses = std::strtoull(argv[9], nullptr, 10);
  const int threads = argc > 10 ? std::atoi(argv[10]) : 2;
  const std::uint64_t first = argc > 11 ? std::strtoull(argv[11], nullptr, 10) : 0;
  const std::vector<std::string> fid{"sim.fidelity=\"" + fidelity + "\""};
  std::vector<std::string> at_truth = fid;
  at_truth.push_back(key + "=" + number_text(truth));
  const DieModel truth_model = compile(load_scene(scene, at_truth), scene);

  const auto t0 = std::chrono::steady_clock::now();
  std::uint64_t covered = 0, covered_profile = 0, open = 0;
  double width = 0.0, ideal = 0.0, est = 0.0, mc = 0.0;
  std::printf("rep,estimate,lo,hi,profile_lo,profile_hi,mc_sd,fisher_halfwidth,covers\n");
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
    const FitResult r = run_fit({{key, lo, hi}}, {{scene, {}, "synthetic", {truth_model.outcome_labels, c.faces}}}, opt);
    const FitParamResult& p = r.params[0];
    const bool cov = p.ci95.lo <= truth && truth <= p.ci95.hi;
    covered += cov;
    covered_profile += p.ci95_profile.lo <= truth && truth <= p.ci95_profile.hi;
    open += p.lo_open || p.hi_open;
    width += p.ci95.hi - p.ci95.lo;
    ideal += 2.0 * p.fisher_halfwidth;
    est += p.estimate;
    mc += p.mc_sd;
    std::printf("%llu,%.6g,%.6g,%.6g,%.6g,%.6g,%.4g,%.4g,%d\n", static_cast<unsigned long long>(rep), p.estimate, p.ci95.lo,
                p.ci95.hi, p.ci95_profile.lo, p.ci95_profile.hi, p.mc_sd, p.fisher_halfwidth, cov ? 1 : 0);
    std::fflush(stdout);
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const Interval ci = wilson_interval(covered, reps);
  const double R = static_cast<double>(reps);
  std::printf("# %s %s %s=%g in [%g, %g], N = %llu observed, %llu tosses per point (last round), %llu repetitions\n",
              scene.c_str(), fidelity.c_str(), key.c_str(), truth, lo, hi, static_cast<unsigned long long>(n),
              static_cast<unsigned long long>(tosses), static_cast<unsigned long long>(reps));
  std::printf("# coverage %llu / %llu = %.3f, 95%% Wilson [%.3f, %.3f]; profile alone %llu; open intervals %llu\n",
              static_cast<unsigned long long>(covered), static_cast<unsigned long long>(reps), covered / R, ci.lo, ci.hi,
              static_cast<unsigned long long>(covered_profile), static_cast<unsigned long long>(open));
  std::printf("# mean estimate %.6g (truth %g); mean width %.4g, mean ideal (Fisher) width %.4g, ratio %.3f; mean MC sd %.4g\n",
              est / R, truth, width / R, ideal / R, width / ideal, mc / R);
  std::printf("# %.1f s, %.2f s per fit\n", s, s / R);
  return 0;
}

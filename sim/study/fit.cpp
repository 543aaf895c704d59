#include "sim/study/auto_pilot.hpp"
#include "sim/study/fit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <Eigen/Dense>
#include <boost/math/distributions/normal.hpp>

#include "sim/body/outcome.hpp"
#include "sim/models/compile.hpp"
#include "sim/models/toss.hpp"
#include "sim/scene/scene.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/study/monte_carlo.hpp"
#include "sim/study/sweep.hpp"

namespace dicesim {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kChi2Level95 = 3.841458820694124;  // chi2_1 quantile 0.95: the profile's cut

// Monomials of total degree <= degree in d <= 3 variables.
struct Basis {
  int d = 1;
  std::vector<std::array<int, 3>> exps;
  Basis(int dims, int degree) : d(dims) {
    for (int total = 0; total <= degree; ++total)
      for (int a = total; a >= 0; --a)
        for (int b = (d > 1 ? total - a : 0); b >= 0; --b) {
          const int c = total - a - b;
          if ((d < 3 && c != 0) || (d < 2 && b != 0)) continue;
          exps.push_back({a, b, c});
        }
  }
  int size() const { return static_cast<int>(exps.size()); }
  VectorXd eval(const std::array<double, 3>& u) const {
    VectorXd phi(size());
    for (int t = 0; t < size(); ++t) {
      double v = 1.0;
      for (int i = 0; i < d; ++i)
        for (int e = 0; e < exps[static_cast<std::size_t>(t)][static_cast<std::size_t>(i)]; ++e) v *= u[static_cast<std::size_t>(i)];
      phi[t] = v;
    }
    return phi;
  }
};

struct Box {
  std::vector<double> lo, hi;
  std::array<double, 3> scaled(const VectorXd& theta) const {
    std::array<double, 3> u{0.0, 0.0, 0.0};
    for (std::size_t i = 0; i < lo.size(); ++i)
      u[i] = (2.0 * theta[static_cast<Eigen::Index>(i)] - lo[i] - hi[i]) / (hi[i] - lo[i]);
    return u;
  }
};

// Counts of one design point and data set, per batch: outcomes in label order, and settled.
struct PointCounts {
  std::vector<std::vector<std::uint64_t>> faces;  // [batch][outcome]
  std::vector<std::uint64_t> settled;             // [batch]
};

// log p~ per data set: a polynomial per outcome, fitted in the box's scaled coordinates.
struct Surrogate {
  Basis basis;
  Box box;
  std::vector<MatrixXd> coef;  // per data set: basis x outcomes

  VectorXd log_p(std::size_t s, const VectorXd& theta) const {
    const VectorXd f = coef[s].transpose() * basis.eval(box.scaled(theta));
    const double top = f.maxCoeff();
    const double lse = top + std::log((f.array() - top).exp().sum());
    return f.array() - lse;
  }
};

// Weighted least squares of log((c + 1/2) / (n + K/2)) with weights n p / (1 - p), the inverse of
// the estimate's binomial variance (the 1/2s keep outcomes never seen finite).
MatrixXd fit_log_p(const Basis& basis, const std::vector<VectorXd>& phi, const std::vector<std::vector<double>>& c,
                   const std::vector<double>& n) {
  const std::size_t J = phi.size(), K = c.front().size();
  MatrixXd coef(basis.size(), static_cast<Eigen::Index>(K));
  MatrixXd A(static_cast<Eigen::Index>(J), basis.size());
  VectorXd y(static_cast<Eigen::Index>(J));
  for (std::size_t k = 0; k < K; ++k) {
    for (std::size_t j = 0; j < J; ++j) {
      const double p = (c[j][k] + 0.5) / (n[j] + 0.5 * static_cast<double>(K));
      const double w = std::sqrt(std::max(n[j], 1.0) * p / std::max(1.0 - p, 1e-12));
      A.row(static_cast<Eigen::Index>(j)) = w * phi[j].transpose();
      y[static_cast<Eigen::Index>(j)] = w * std::log(p);
    }
    coef.col(static_cast<Eigen::Index>(k)) = A.colPivHouseholderQr().solve(y);
  }
  return coef;
}

using Objective = std::function<double(const VectorXd&)>;

// Compass search inside the box from x with initial steps `step` (per dimension): try +-step along
// each axis, move on improvement, halve when nothing improves. Smooth, low-dimensional objective.
VectorXd pattern_search(const Objective& f, const Box& box, VectorXd x, VectorXd step, double* fx_out = nullptr) {
  double fx = f(x);
  const Eigen::Index d = x.size();
  for (int iter = 0; iter < 20000; ++iter) {
    bool moved = false;
    for (Eigen::Index i = 0; i < d; ++i)
      for (const double sign : {1.0, -1.0}) {
        VectorXd y = x;
        y[i] = std::clamp(x[i] + sign * step[i], box.lo[static_cast<std::size_t>(i)], box.hi[static_cast<std::size_t>(i)]);
        if (y[i] == x[i]) continue;
        const double fy = f(y);
        if (fy > fx) {
          x = y;
          fx = fy;
          moved = true;
        }
      }
    if (!moved) {
      step *= 0.5;
      bool small = true;
      for (Eigen::Index i = 0; i < d; ++i)
        small = small && step[i] < 1e-11 * (box.hi[static_cast<std::size_t>(i)] - box.lo[static_cast<std::size_t>(i)]);
      if (small) break;
    }
  }
  if (fx_out) *fx_out = fx;
  return x;
}

// The grid of g values per dimension over the box (ends included exactly), first dimension fastest.
std::vector<VectorXd> box_grid(const Box& box, int g) {
  const int d = static_cast<int>(box.lo.size());
  int total = 1;
  for (int i = 0; i < d; ++i) total *= g;
  std::vector<VectorXd> pts;
  pts.reserve(static_cast<std::size_t>(total));
  for (int idx = 0; idx < total; ++idx) {
    VectorXd x(d);
    int r = idx;
    for (int i = 0; i < d; ++i) {
      const int gi = r % g;
      r /= g;
      const auto ii = static_cast<std::size_t>(i);
      x[i] = gi == g - 1 ? box.hi[ii] : box.lo[ii] + (box.hi[ii] - box.lo[ii]) * gi / (g - 1);
    }
    pts.push_back(std::move(x));
  }
  return pts;
}

// The maximum over the box: a grid (fine in one dimension, coarse in three), then the compass search.
VectorXd maximize(const Objective& f, const Box& box, double* fx_out = nullptr) {
  const int d = static_cast<int>(box.lo.size());
  const int g = d == 1 ? 401 : d == 2 ? 61 : 21;
  VectorXd best;
  double fbest = -std::numeric_limits<double>::infinity();
  for (const VectorXd& x : box_grid(box, g)) {
    const double fx = f(x);
    if (fx > fbest) {
      fbest = fx;
      best = x;
    }
  }
  VectorXd step(d);
  for (int i = 0; i < d; ++i) step[i] = (box.hi[static_cast<std::size_t>(i)] - box.lo[static_cast<std::size_t>(i)]) / (g - 1);
  return pattern_search(f, box, best, step, fx_out);
}

std::string labels_text(const std::vector<int>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
  return s;
}

// auto in a fit: the scene moves across the box, and a pilot at one point says nothing of the others
// (nor may the model change between points of one surrogate).
constexpr const char* kFitAutoReason =
    "auto: `impulse` (no pilot): a fit moves the scene across its box, where a cheaper model shown adequate at one "
    "point may not be at another, and one model must serve every point";

class Fitter {
 public:
  Fitter(const std::vector<FitParam>& params, const std::vector<FitData>& data, const FitOptions& opt)
      : params_(params), data_(data), opt_(opt), d_(static_cast<int>(params.size())) {}

  FitResult run();

 private:
  std::vector<std::string> overrides_at(std::size_t s, const VectorXd& theta) const {
    std::vector<std::string> all = opt_.overrides;
    all.insert(all.end(), data_[s].overrides.begin(), data_[s].overrides.end());
    for (int i = 0; i < d_; ++i) all.push_back(params_[static_cast<std::size_t>(i)].key + "=" + number_text(theta[i]));
    return all;
  }
  DieModel model_at(std::size_t s, const VectorXd& theta) const {
    DieModel m = compile(load_scene(data_[s].scene, overrides_at(s, theta)), data_[s].scene);
    resolve_auto_unmeasured(m, kFitAutoReason);
    return m;
  }
  std::vector<VectorXd> grid(const Box& box) const { return box_grid(box, fit_grid_points(d_)); }
  // Tosses every model with indices 0..tosses-1 in `batches` batches on the thread pool.
  std::vector<PointCounts> simulate(const std::vector<DieModel>& models, std::uint64_t tosses, const std::string& stage);
  // One stage's counts, [data set][point], models[s][j] at points[j]: tossed here, or taken from
  // opt_.given (a sharded fit: FitPointCounts, FitStageIncomplete).
  std::vector<std::vector<PointCounts>> stage_counts(const std::vector<std::vector<DieModel>>& models,
                                                     const std::vector<VectorXd>& points, std::uint64_t tosses,
                                                     const std::string& label);
  Surrogate fit_surrogate(const Box& box, const std::vector<VectorXd>& design, const std::vector<std::vector<PointCounts>>& counts,
                          int skip_batch) const;
  FitParamResult profile_param(int i, const Surrogate& sur, const Box& box, const VectorXd& theta, double lmax,
                               double mc_sd) const;
  void check_identifiable(FitParamResult& pr, int i, const std::vector<VectorXd>& design,
                          const std::vector<std::vector<PointCounts>>& counts) const;
  double loglik(const Surrogate& sur, const VectorXd& theta) const {
    double l = 0.0;
    for (std::size_t s = 0; s < data_.size(); ++s) l += n_[s].dot(sur.log_p(s, theta));
    return l;
  }

  const std::vector<FitParam>& params_;
  const std::vector<FitData>& data_;
  const FitOptions& opt_;
  int d_;
  std::vector<VectorXd> n_;                 // observed counts per data set, in the model's label order
  std::vector<std::vector<int>> labels_;    // per data set
  std::uint64_t done_ = 0, total_ = 0;      // tosses, for progress
  std::uint64_t simulated_ = 0;
  std::uint64_t tosses_ = 0;               // per point in the last round
  int stage_ = 0;                          // stages counted so far (FitPointCounts::stage)
};

std::vector<std::vector<PointCounts>> Fitter::stage_counts(const std::vector<std::vector<DieModel>>& models,
                                                           const std::vector<VectorXd>& points, std::uint64_t tosses,
                                                           const std::string& label) {
  const int stage = stage_++;
  const std::size_t S = models.size(), J = points.size();
  std::vector<std::vector<PointCounts>> out(S);
  if (!opt_.given) {
    for (std::size_t s = 0; s < S; ++s) out[s] = simulate(models[s], tosses, label);
    return out;
  }
  const auto B = static_cast<std::size_t>(opt_.batches);
  std::vector<const FitPointCounts*> found(S * J, nullptr);
  for (const FitPointCounts& g : *opt_.given) {
    if (g.stage != stage) continue;
    const std::string where = "stage " + std::to_string(stage) + " point " + std::to_string(g.point);
    if (g.point >= S * J)
      throw SceneError(g.origin, "point", where,
                       "this fit's stage " + std::to_string(stage) + " has " + std::to_string(S * J) + " points (a part of another fit?)");
    const std::size_t s = g.point / J, j = g.point % J;
    bool same = g.tosses == tosses && g.theta.size() == static_cast<std::size_t>(d_) && g.faces.size() == B && g.settled.size() == B;
    for (int i = 0; same && i < d_; ++i) same = g.theta[static_cast<std::size_t>(i)] == points[j][i];
    for (std::size_t b = 0; same && b < B; ++b) same = g.faces[b].size() == labels_[s].size();
    if (!same)
      throw SceneError(g.origin, "point", where, "its keys' values, tosses or batches are not this fit's (a part of another fit?)");
    if (found[g.point])
      throw SceneError(g.origin, "point", where,
                       "also counted in " + found[g.point]->origin + " (overlapping parts: each point may be counted once)");
    found[g.point] = &g;
  }
  FitStageIncomplete inc;
  inc.stage = stage;
  inc.label = label;
  inc.stage_points = S * J;
  for (std::size_t f = 0; f < S * J; ++f)
    if (!found[f]) inc.missing.push_back(f);
  if (inc.missing.empty()) {
    for (std::size_t f = 0; f < S * J; ++f) out[f / J].push_back({found[f]->faces, found[f]->settled});
    simulated_ += tosses * S * J;  // as an unsharded fit counts them
    return out;
  }
  if (opt_.toss_shard.count > 0) {  // a pass: this shard's block of the stage, then stop
    const IndexRange block = shard_range(S * J, opt_.toss_shard);
    std::vector<std::size_t> left;
    for (const std::size_t f : inc.missing) {
      if (f < block.first || f >= block.first + block.tosses) {
        left.push_back(f);
        continue;
      }
      const std::size_t s = f / J, j = f % J;
      PointCounts pc = std::move(simulate({models[s][j]}, tosses, label)[0]);
      FitPointCounts t;
      t.stage = stage;
      t.point = f;
      t.theta.assign(points[j].data(), points[j].data() + points[j].size());
      t.tosses = tosses;
      t.faces = std::move(pc.faces);
      t.settled = std::move(pc.settled);
      inc.tossed.push_back(std::move(t));
    }
    inc.missing = std::move(left);
  }
  throw inc;
}

std::vector<PointCounts> Fitter::simulate(const std::vector<DieModel>& models, std::uint64_t tosses, const std::string& stage) {
  const int B = opt_.batches;
  struct Job {
    std::size_t model;
    int batch;
    std::uint64_t lo, hi;
  };
  std::vector<Job> jobs;
  constexpr std::uint64_t kJob = 256;  // small: the last jobs of a round balance the threads
  for (std::size_t m = 0; m < models.size(); ++m)
    for (int b = 0; b < B; ++b) {
      const std::uint64_t lo = tosses * static_cast<std::uint64_t>(b) / static_cast<std::uint64_t>(B);
      const std::uint64_t hi = tosses * static_cast<std::uint64_t>(b + 1) / static_cast<std::uint64_t>(B);
      for (std::uint64_t a = lo; a < hi; a += kJob) jobs.push_back({m, b, a, std::min(hi, a + kJob)});
    }
  std::vector<PointCounts> out(models.size());
  for (std::size_t m = 0; m < models.size(); ++m) {
    out[m].faces.assign(static_cast<std::size_t>(B), std::vector<std::uint64_t>(static_cast<std::size_t>(models[m].outcomes()), 0));
    out[m].settled.assign(static_cast<std::size_t>(B), 0);
  }
  std::atomic<std::size_t> next{0};
  std::atomic<std::uint64_t> done{done_};
  std::mutex mu;
  auto work = [&] {
    for (;;) {
      if (opt_.cancel && opt_.cancel->load(std::memory_order_relaxed)) return;
      const std::size_t j = next.fetch_add(1, std::memory_order_relaxed);
      if (j >= jobs.size()) return;
      const Job& job = jobs[j];
      RunCounts local(models[job.model].outcomes());
      for (std::uint64_t i = job.lo; i < job.hi; ++i) local.add(toss(models[job.model], opt_.seed, i));
      {
        std::lock_guard lock(mu);
        auto& f = out[job.model].faces[static_cast<std::size_t>(job.batch)];
        for (std::size_t k = 0; k < f.size(); ++k) f[k] += local.faces[k];
        out[job.model].settled[static_cast<std::size_t>(job.batch)] += local.settled;
      }
      const std::uint64_t now = done.fetch_add(job.hi - job.lo) + (job.hi - job.lo);
      if (opt_.progress) opt_.progress(stage, now, total_);
    }
  };
  {
    std::vector<std::jthread> pool;
    for (int t = 1; t < std::max(1, opt_.threads); ++t) pool.emplace_back(work);
    work();
  }
  if (opt_.cancel && opt_.cancel->load()) throw std::runtime_error("cancelled");
  done_ = done.load();
  simulated_ += tosses * models.size();
  return out;
}

Surrogate Fitter::fit_surrogate(const Box& box, const std::vector<VectorXd>& design,
                                const std::vector<std::vector<PointCounts>>& counts, int skip_batch) const {
  Surrogate sur{Basis(d_, fit_surrogate_degree(d_)), box, {}};
  std::vector<VectorXd> phi;
  for (const VectorXd& x : design) phi.push_back(sur.basis.eval(box.scaled(x)));
  for (std::size_t s = 0; s < data_.size(); ++s) {
    std::vector<std::vector<double>> c;
    std::vector<double> n;
    for (const PointCounts& pc : counts[s]) {
      std::vector<double> ck(pc.faces.front().size(), 0.0);
      double nk = 0.0;
      for (std::size_t b = 0; b < pc.faces.size(); ++b) {
        if (static_cast<int>(b) == skip_batch) continue;
        for (std::size_t k = 0; k < ck.size(); ++k) ck[k] += static_cast<double>(pc.faces[b][k]);
        nk += static_cast<double>(pc.settled[b]);
      }
      c.push_back(std::move(ck));
      n.push_back(nk);
    }
    sur.coef.push_back(fit_log_p(sur.basis, phi, c, n));
  }
  return sur;
}

// Parameter i's profile over the box (the others maximised, warm-started along it), its 95%
// interval and the interval widened by the Monte Carlo sd.
FitParamResult Fitter::profile_param(int i, const Surrogate& sur, const Box& box, const VectorXd& theta, double lmax,
                                     double mc_sd) const {
  const auto ii = static_cast<std::size_t>(i);
  FitParamResult pr;
  pr.key = params_[ii].key;
  pr.lo = params_[ii].lo;
  pr.hi = params_[ii].hi;
  auto profile_at = [&, i](double t, VectorXd& warm) {
    if (d_ == 1) {
      VectorXd x(1);
      x[0] = t;
      return loglik(sur, x);
    }
    Box sub;
    std::vector<int> dims;
    for (int k = 0; k < d_; ++k)
      if (k != i) {
        dims.push_back(k);
        sub.lo.push_back(box.lo[static_cast<std::size_t>(k)]);
        sub.hi.push_back(box.hi[static_cast<std::size_t>(k)]);
      }
    auto g = [&](const VectorXd& y) {
      VectorXd x(d_);
      x[i] = t;
      for (std::size_t k = 0; k < dims.size(); ++k) x[dims[k]] = y[static_cast<Eigen::Index>(k)];
      return loglik(sur, x);
    };
    VectorXd st(static_cast<Eigen::Index>(dims.size()));
    for (std::size_t k = 0; k < dims.size(); ++k) st[static_cast<Eigen::Index>(k)] = 0.05 * (sub.hi[k] - sub.lo[k]);
    double fw = 0.0, ft = 0.0;
    VectorXd from_theta(static_cast<Eigen::Index>(dims.size()));
    for (std::size_t k = 0; k < dims.size(); ++k) from_theta[static_cast<Eigen::Index>(k)] = theta[dims[k]];
    VectorXd a = pattern_search(g, sub, warm.size() ? warm : from_theta, st, &fw);
    VectorXd b2 = pattern_search(g, sub, from_theta, st, &ft);
    warm = fw >= ft ? a : b2;
    return std::max(fw, ft);
  };
  constexpr int kProfile = 101;
  const double blo = box.lo[ii], bhi = box.hi[ii];
  VectorXd warm;
  // From the estimate outwards on both sides, so the warm start follows the ridge.
  std::vector<double> grid_t;
  for (int k = 0; k < kProfile; ++k) grid_t.push_back(k == kProfile - 1 ? bhi : blo + (bhi - blo) * k / (kProfile - 1));
  std::vector<double> prof(grid_t.size());
  const auto centre = static_cast<std::size_t>(std::lower_bound(grid_t.begin(), grid_t.end(), theta[i]) - grid_t.begin());
  for (std::size_t k = centre; k < grid_t.size(); ++k) prof[k] = profile_at(grid_t[k], warm);
  warm = VectorXd();
  for (std::size_t k = centre; k-- > 0;) prof[k] = profile_at(grid_t[k], warm);
  double lbest = lmax;
  for (const double v : prof) lbest = std::max(lbest, v);
  for (std::size_t k = 0; k < grid_t.size(); ++k) pr.profile.push_back({grid_t[k], 2.0 * (lbest - prof[k])});
  // The interval is the hull of the confidence set {t : 2 (l_max - l_profile(t)) < 3.84}: each
  // end is found from the box's edge inwards (the first grid value inside the set, then
  // bisection), so a second mode that the data cannot tell from the first stays inside it.
  auto end_on = [&](int dir, bool& open) {
    VectorXd w;
    const long size = static_cast<long>(grid_t.size());
    auto inside_set = [&](long k) { return 2.0 * (lbest - prof[static_cast<std::size_t>(k)]) < kChi2Level95; };
    long k = dir < 0 ? 0 : size - 1;
    if (inside_set(k)) {
      open = true;
      return dir < 0 ? blo : bhi;
    }
    while (!inside_set(k - dir) && (k - dir) != static_cast<long>(centre)) k -= dir;
    double out = grid_t[static_cast<std::size_t>(k)], in = grid_t[static_cast<std::size_t>(k - dir)];
    if (!inside_set(k - dir)) in = theta[i];  // only the estimate's own neighbourhood is inside
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (out + in);
      (2.0 * (lbest - profile_at(mid, w)) >= kChi2Level95 ? out : in) = mid;
    }
    open = false;
    return 0.5 * (out + in);
  };
  bool lo_open = false, hi_open = false;
  pr.ci95_profile = {end_on(-1, lo_open), end_on(+1, hi_open)};
  pr.lo_open = lo_open;  // run() widens a narrowed box whose edge the set reaches
  pr.hi_open = hi_open;
  pr.box_lo = blo;
  pr.box_hi = bhi;
  pr.estimate = theta[i];
  pr.mc_sd = mc_sd;
  const double z = kZ95 * pr.mc_sd;
  pr.ci95.lo = std::max(params_[ii].lo, pr.estimate - std::hypot(pr.estimate - pr.ci95_profile.lo, z));
  pr.ci95.hi = std::min(params_[ii].hi, pr.estimate + std::hypot(pr.ci95_profile.hi - pr.estimate, z));
  pr.mc_large = pr.mc_sd > 0.5 * (pr.ci95_profile.hi - pr.ci95_profile.lo) / (2.0 * kZ95);
  return pr;
}

// Does key i move any outcome's probability by more than the Monte Carlo noise? Every pair of
// design points that differ in key i alone, every data set and outcome: the difference of the
// two frequencies, and its standard error from the batches (each batch is the same toss indices at
// both points, so the common random numbers' correlation is in it). The key is identifiable when
// some |difference| exceeds z * se, z the two-sided 95% level Bonferroni-corrected for the number
// of comparisons (a difference with se = 0 counts when it is not 0).
void Fitter::check_identifiable(FitParamResult& pr, int i, const std::vector<VectorXd>& design,
                                const std::vector<std::vector<PointCounts>>& counts) const {
  struct Cmp {
    std::size_t s, a, b, k;
  };
  std::vector<Cmp> cmps;
  for (std::size_t a = 0; a < design.size(); ++a)
    for (std::size_t b = a + 1; b < design.size(); ++b) {
      bool only_i = design[a][i] != design[b][i];
      for (int j = 0; j < d_ && only_i; ++j) only_i = j == i || design[a][j] == design[b][j];
      if (!only_i) continue;
      for (std::size_t s = 0; s < counts.size(); ++s)
        for (std::size_t k = 0; k < labels_[s].size(); ++k) cmps.push_back({s, a, b, k});
    }
  const double alpha = 0.05 / static_cast<double>(std::max<std::size_t>(cmps.size(), 1));
  pr.shift_z_level = boost::math::quantile(boost::math::complement(boost::math::normal(), alpha / 2.0));
  pr.shift_z = 0.0;
  pr.identifiable = false;
  for (const Cmp& c : cmps) {
    const PointCounts& A = counts[c.s][c.a];
    const PointCounts& B = counts[c.s][c.b];
    const std::size_t nb = A.settled.size();
    std::vector<double> diff;
    double ca = 0.0, na = 0.0, cb = 0.0, nbt = 0.0;
    for (std::size_t t = 0; t < nb; ++t) {
      ca += static_cast<double>(A.faces[t][c.k]);
      na += static_cast<double>(A.settled[t]);
      cb += static_cast<double>(B.faces[t][c.k]);
      nbt += static_cast<double>(B.settled[t]);
      if (A.settled[t] && B.settled[t])
        diff.push_back(static_cast<double>(B.faces[t][c.k]) / static_cast<double>(B.settled[t]) -
                       static_cast<double>(A.faces[t][c.k]) / static_cast<double>(A.settled[t]));
    }
    if (na <= 0.0 || nbt <= 0.0 || diff.size() < 2) continue;
    const double d = cb / nbt - ca / na;
    double mean = 0.0, var = 0.0;
    for (const double x : diff) mean += x / static_cast<double>(diff.size());
    for (const double x : diff) var += (x - mean) * (x - mean) / static_cast<double>(diff.size() - 1);
    const double se = std::sqrt(var / static_cast<double>(diff.size()));
    if (se > 0.0) {
      pr.shift_z = std::max(pr.shift_z, std::abs(d) / se);
      if (std::abs(d) > pr.shift_z_level * se) pr.identifiable = true;
    } else if (d != 0.0) {
      pr.shift_z = std::numeric_limits<double>::infinity();
      pr.identifiable = true;
    }
  }
}

FitResult Fitter::run() {
  const auto t0 = std::chrono::steady_clock::now();
  if (d_ < 1 || d_ > 3) throw SceneError("dicesim fit", "--param", std::to_string(d_) + " parameters", "fit takes 1 to 3 parameters");
  for (std::size_t i = 0; i < params_.size(); ++i) {
    const FitParam& p = params_[i];
    if (!(p.lo < p.hi) || !std::isfinite(p.lo) || !std::isfinite(p.hi))
      throw SceneError("dicesim fit", "--param", p.key + "=" + number_text(p.lo) + ":" + number_text(p.hi),
                       "LO must be below HI, both finite");
    for (std::size_t j = 0; j < i; ++j)
      if (params_[j].key == p.key) throw SceneError("dicesim fit", "--param", p.key, "given twice");
  }
  if (data_.empty()) throw SceneError("dicesim fit", "--data", "", "at least one data set is needed");
  if (opt_.rounds < 1 || opt_.rounds > 10) throw SceneError("dicesim fit", "--rounds", std::to_string(opt_.rounds), "must be in [1, 10]");
  if (opt_.batches < 4 || opt_.batches > 1000)
    throw SceneError("dicesim fit", "batches", std::to_string(opt_.batches), "must be in [4, 1000]");
  const std::uint64_t min_tosses = static_cast<std::uint64_t>(opt_.batches) << (opt_.rounds - 1);
  tosses_ = opt_.tosses ? opt_.tosses : fit_auto_tosses(data_);
  if (tosses_ < std::max<std::uint64_t>(min_tosses, 1000))
    throw SceneError("dicesim fit", "--tosses", std::to_string(tosses_),
                     "must be at least " + std::to_string(std::max<std::uint64_t>(min_tosses, 1000)));

  Box box;
  for (const FitParam& p : params_) {
    box.lo.push_back(p.lo);
    box.hi.push_back(p.hi);
  }
  const Box range = box;
  std::vector<VectorXd> design = grid(box);
  const int R = opt_.rounds;
  const std::size_t S = data_.size();
  auto round_tosses = [&](int r) { return tosses_ >> (R - 1 - r); };
  for (int r = 0; r < R; ++r) total_ += round_tosses(r) * design.size() * S;
  total_ += tosses_ * S;  // the fitted probabilities at the estimate

  // Every model of the first round is compiled before the first toss: a bad key or value (the
  // grid holds LO and HI of every parameter) fails at once.
  std::vector<std::vector<DieModel>> models(S);
  for (std::size_t s = 0; s < S; ++s) {
    for (const VectorXd& x : design) models[s].push_back(model_at(s, x));
    labels_.push_back(models[s].front().outcome_labels);
    for (const DieModel& m : models[s])
      if (m.outcome_labels != labels_[s])
        throw SceneError(data_[s].scene, "outcomes", labels_text(m.outcome_labels),
                         "the fitted keys must not change the die's outcomes (at the range's first value: " + labels_text(labels_[s]) + ")");
    const FaceCounts& obs = data_[s].observed;
    if (obs.labels.size() != obs.counts.size()) throw SceneError(data_[s].source, "counts", "", "labels and counts differ in number");
    VectorXd n = VectorXd::Zero(static_cast<Eigen::Index>(labels_[s].size()));
    for (std::size_t i = 0; i < obs.labels.size(); ++i) {
      const auto it = std::find(labels_[s].begin(), labels_[s].end(), obs.labels[i]);
      if (it == labels_[s].end())
        throw SceneError(data_[s].source, "face", std::to_string(obs.labels[i]),
                         "the die of " + data_[s].scene + " has no such outcome; its outcomes: " + labels_text(labels_[s]));
      n[it - labels_[s].begin()] += static_cast<double>(obs.counts[i]);
    }
    // The data must be of this die: every outcome it has named (a count of 0 when never seen).
    std::vector<int> missing;
    for (const int l : labels_[s])
      if (std::find(obs.labels.begin(), obs.labels.end(), l) == obs.labels.end()) missing.push_back(l);
    if (!missing.empty()) {
      std::vector<int> given = obs.labels;
      std::sort(given.begin(), given.end());
      throw SceneError(data_[s].source, "face", labels_text(given),
                       "these outcome labels are not those of the die of " + data_[s].scene + " (" + labels_text(labels_[s]) +
                           "): " + labels_text(missing) + " missing; list every outcome of the die, with count 0 if never seen");
    }
    if (n.sum() <= 0.0) throw SceneError(data_[s].source, "counts", "", "all counts are 0");
    n_.push_back(n);
  }

  FitResult res;
  res.fidelity = to_string(models.front().front().fidelity);
  res.fidelity_reason = models.front().front().fidelity_reason;
  Surrogate sur{Basis(d_, 0), box, {}};
  std::vector<std::vector<PointCounts>> counts;
  VectorXd theta(d_);
  int widenings = 0;
  for (int r = 0; r < R; ++r) {
    if (r > 0) {
      for (std::size_t s = 0; s < S; ++s) {
        models[s].clear();
        for (const VectorXd& x : design) models[s].push_back(model_at(s, x));
      }
    }
    const std::string stage = "round " + std::to_string(r + 1) + "/" + std::to_string(R);
    counts = stage_counts(models, design, round_tosses(r), stage);
    if (r == 0) {
      // A key that moves no outcome beyond the noise cannot be fitted: say so, estimate nothing.
      res.params.clear();
      for (int i = 0; i < d_; ++i) {
        FitParamResult pr;
        pr.key = params_[static_cast<std::size_t>(i)].key;
        pr.lo = pr.box_lo = params_[static_cast<std::size_t>(i)].lo;
        pr.hi = pr.box_hi = params_[static_cast<std::size_t>(i)].hi;
        check_identifiable(pr, i, design, counts);
        res.params.push_back(pr);
      }
      res.estimated = std::any_of(res.params.begin(), res.params.end(), [](const FitParamResult& p) { return p.identifiable; });
      if (!res.estimated) {
        constexpr double nan = std::numeric_limits<double>::quiet_NaN();
        for (FitParamResult& pr : res.params) {
          pr.estimate = pr.mc_sd = pr.fisher_halfwidth = nan;
          pr.ci95 = pr.ci95_profile = {nan, nan};
        }
        FitRound fr;
        fr.box_lo = box.lo;
        fr.box_hi = box.hi;
        fr.points = design.size();
        fr.tosses_per_point = round_tosses(r);
        res.rounds.push_back(fr);
        res.loglik = nan;
        res.gof = {nan, 0, nan};
        for (std::size_t s = 0; s < S; ++s) {
          FitDataResult dr;
          dr.scene = data_[s].scene;
          dr.overrides = data_[s].overrides;
          dr.source = data_[s].source;
          dr.labels = labels_[s];
          for (Eigen::Index k = 0; k < n_[s].size(); ++k) dr.observed.push_back(static_cast<std::uint64_t>(n_[s][k]));
          dr.gof = {nan, 0, nan};
          res.data.push_back(std::move(dr));
        }
        res.simulated_tosses = simulated_;
        res.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return res;
      }
    }
    sur = fit_surrogate(box, design, counts, -1);
    double lmax = 0.0;
    theta = maximize([&](const VectorXd& x) { return loglik(sur, x); }, box, &lmax);

    // Monte Carlo spread of the estimate: refitted without each batch (the same batch leaves every
    // point, which keeps the common random numbers), searched from the full estimate.
    const int B = opt_.batches;
    std::vector<VectorXd> jk;
    VectorXd step(d_);
    for (int i = 0; i < d_; ++i) step[i] = 0.02 * (box.hi[static_cast<std::size_t>(i)] - box.lo[static_cast<std::size_t>(i)]);
    for (int b = 0; b < B; ++b) {
      const Surrogate sb = fit_surrogate(box, design, counts, b);
      jk.push_back(pattern_search([&](const VectorXd& x) { return loglik(sb, x); }, box, theta, step));
    }
    VectorXd mean = VectorXd::Zero(d_);
    for (const VectorXd& t : jk) mean += t / static_cast<double>(B);
    VectorXd var = VectorXd::Zero(d_);
    for (const VectorXd& t : jk) var += (t - mean).cwiseAbs2();
    const VectorXd mc_sd = (var * (static_cast<double>(B - 1) / B)).cwiseSqrt();

    // Profiles: each parameter on a grid over the box, the others maximised.
    std::vector<FitParamResult> checked = std::move(res.params);
    res.params.clear();
    for (int i = 0; i < d_; ++i) {
      res.params.push_back(profile_param(i, sur, box, theta, lmax, mc_sd[i]));
      if (static_cast<std::size_t>(i) < checked.size()) {
        res.params.back().identifiable = checked[static_cast<std::size_t>(i)].identifiable;
        res.params.back().shift_z = checked[static_cast<std::size_t>(i)].shift_z;
        res.params.back().shift_z_level = checked[static_cast<std::size_t>(i)].shift_z_level;
      }
    }
    FitRound fr;
    fr.box_lo = box.lo;
    fr.box_hi = box.hi;
    fr.points = design.size();
    fr.tosses_per_point = round_tosses(r);
    for (int i = 0; i < d_; ++i) fr.estimate.push_back(theta[i]);
    res.loglik = lmax;

    // A set reaching a narrowed box's edge was cut off by the box, not bounded by the data: widen
    // that side (by the box's width, within LO..HI) and refit this round.
    Box wider = box;
    bool widen = false;
    for (int i = 0; i < d_; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      const double w = box.hi[ii] - box.lo[ii];
      if (res.params[ii].lo_open && box.lo[ii] > range.lo[ii]) {
        wider.lo[ii] = std::max(range.lo[ii], box.lo[ii] - w);
        widen = true;
      }
      if (res.params[ii].hi_open && box.hi[ii] < range.hi[ii]) {
        wider.hi[ii] = std::min(range.hi[ii], box.hi[ii] + w);
        widen = true;
      }
    }
    fr.widened = widen && widenings < kFitMaxWidenings;
    res.rounds.push_back(fr);
    if (fr.widened) {
      ++widenings;
      box = wider;
      design = grid(box);
      total_ += round_tosses(r) * design.size() * S;
      --r;  // the same round again, in the wider box (its models are compiled at the loop's top)
      continue;
    }

    if (r + 1 < R) {  // the next box: the interval widened 2.5x about the estimate, inside LO..HI
      Box next;
      for (int i = 0; i < d_; ++i) {
        const auto ii = static_cast<std::size_t>(i);
        const FitParamResult& pr = res.params[ii];
        const double min_w = 1e-3 * (range.hi[ii] - range.lo[ii]);
        double lo = std::max(range.lo[ii], theta[i] - std::max(2.5 * (theta[i] - pr.ci95.lo), min_w));
        double hi = std::min(range.hi[ii], theta[i] + std::max(2.5 * (pr.ci95.hi - theta[i]), min_w));
        next.lo.push_back(lo);
        next.hi.push_back(hi);
      }
      box = next;
      design = grid(box);
    }
  }

  // The ideal (Fisher) half-widths at the estimate: I = sum_s N_s sum_k grad p_k grad p_k^T / p_k.
  MatrixXd info = MatrixXd::Zero(d_, d_);
  for (std::size_t s = 0; s < S; ++s) {
    const VectorXd p = sur.log_p(s, theta).array().exp();
    MatrixXd grad(p.size(), d_);
    for (int i = 0; i < d_; ++i) {
      const double h = 1e-4 * (box.hi[static_cast<std::size_t>(i)] - box.lo[static_cast<std::size_t>(i)]);
      VectorXd a = theta, b = theta;
      a[i] += h;
      b[i] -= h;
      grad.col(i) = (sur.log_p(s, a).array().exp() - sur.log_p(s, b).array().exp()) / (2.0 * h);
    }
    for (Eigen::Index k = 0; k < p.size(); ++k) info += n_[s].sum() * grad.row(k).transpose() * grad.row(k) / p[k];
  }
  // Over the identifiable keys only; the others get no estimate or interval.
  std::vector<int> known;
  for (int i = 0; i < d_; ++i)
    if (res.params[static_cast<std::size_t>(i)].identifiable) known.push_back(i);
  MatrixXd sub(static_cast<Eigen::Index>(known.size()), static_cast<Eigen::Index>(known.size()));
  for (std::size_t a = 0; a < known.size(); ++a)
    for (std::size_t b = 0; b < known.size(); ++b)
      sub(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) = info(known[a], known[b]);
  const Eigen::FullPivLU<MatrixXd> lu(sub);
  const auto nk = static_cast<Eigen::Index>(known.size());
  const MatrixXd cov = lu.isInvertible() ? MatrixXd(lu.inverse()) : MatrixXd::Constant(nk, nk, std::numeric_limits<double>::quiet_NaN());
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  for (FitParamResult& pr : res.params) pr.fisher_halfwidth = nan;
  for (std::size_t a = 0; a < known.size(); ++a) {
    const double v = cov(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(a));
    res.params[static_cast<std::size_t>(known[a])].fisher_halfwidth = v > 0.0 ? kZ95 * std::sqrt(v) : nan;
  }
  for (FitParamResult& pr : res.params)
    if (!pr.identifiable) {
      pr.estimate = pr.mc_sd = nan;
      pr.ci95 = pr.ci95_profile = {nan, nan};
    }

  // The fitted probabilities: simulated at the estimate, with the goodness of fit.
  double stat = 0.0;
  int dof = 0;
  std::vector<std::vector<DieModel>> at(S);
  for (std::size_t s = 0; s < S; ++s) at[s].push_back(model_at(s, theta));
  const std::vector<std::vector<PointCounts>> fitted = stage_counts(at, {theta}, tosses_, "fitted");
  for (std::size_t s = 0; s < S; ++s) {
    const PointCounts& pc = fitted[s][0];
    FitDataResult dr;
    dr.scene = data_[s].scene;
    dr.overrides = data_[s].overrides;
    dr.source = data_[s].source;
    dr.labels = labels_[s];
    if (at[s][0].outcome_labels == dr.labels) dr.names = outcome_names(at[s][0]);
    dr.fitted_tosses = tosses_;
    std::uint64_t settled = 0;
    std::vector<std::uint64_t> f(labels_[s].size(), 0);
    for (std::size_t b = 0; b < pc.faces.size(); ++b) {
      settled += pc.settled[b];
      for (std::size_t k = 0; k < f.size(); ++k) f[k] += pc.faces[b][k];
    }
    for (std::size_t k = 0; k < f.size(); ++k) {
      dr.observed.push_back(static_cast<std::uint64_t>(n_[s][static_cast<Eigen::Index>(k)]));
      dr.fitted.push_back(settled ? static_cast<double>(f[k]) / static_cast<double>(settled) : 0.0);
    }
    dr.gof = chi2_against(dr.observed, dr.fitted);
    stat += dr.gof.statistic;
    dof += dr.gof.dof;
    res.data.push_back(std::move(dr));
  }
  res.gof.statistic = stat;
  res.gof.dof = dof - d_;
  res.gof.p_value = res.gof.dof > 0 ? chi2_p_value(stat, res.gof.dof) : std::numeric_limits<double>::quiet_NaN();
  res.simulated_tosses = simulated_;
  res.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace

std::uint64_t fit_auto_tosses(const std::vector<FitData>& data) {
  std::uint64_t observed_max = 0;
  for (const FitData& d : data) observed_max = std::max(observed_max, d.observed.total());
  return std::max<std::uint64_t>(kAutoTossesMin, kAutoTossesPerObserved * observed_max);
}

int fit_grid_points(int params) { return params <= 1 ? 7 : params == 2 ? 5 : 4; }
int fit_surrogate_degree(int params) { return params <= 2 ? 3 : 2; }

FitParam parse_fit_param(const std::string& text, const std::string& origin) {
  const auto eq = text.rfind('=');
  const auto colon = eq == std::string::npos ? std::string::npos : text.find(':', eq);
  auto bad = [&](const std::string& why) { return SceneError(origin, "--param", text, why); };
  if (eq == std::string::npos || eq == 0 || colon == std::string::npos)
    throw bad("expected KEY=LO:HI, e.g. floor.restitution=0.2:0.8");
  FitParam p;
  p.key = text.substr(0, eq);
  const std::string a = text.substr(eq + 1, colon - eq - 1), b = text.substr(colon + 1);
  char* ea = nullptr;
  char* eb = nullptr;
  p.lo = std::strtod(a.c_str(), &ea);
  p.hi = std::strtod(b.c_str(), &eb);
  if (a.empty() || b.empty() || *ea != '\0' || *eb != '\0' || !std::isfinite(p.lo) || !std::isfinite(p.hi))
    throw bad("LO and HI must be numbers, e.g. floor.restitution=0.2:0.8");
  if (!(p.lo < p.hi)) throw bad("LO must be below HI");
  return p;
}

FitResult run_fit(const std::vector<FitParam>& params, const std::vector<FitData>& data, const FitOptions& opt) {
  return Fitter(params, data, opt).run();
}

}  // namespace dicesim

#include "sim/study/restitution_fit.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>
#include <boost/math/distributions/students_t.hpp>

namespace dicesim {
namespace {

RestitutionEstimate estimate_from_ratios(std::vector<double> ratios) {
  RestitutionEstimate e;
  e.n = ratios.size();
  if (e.n < 2) throw std::invalid_argument("need at least 2 impacts for an interval, got " + std::to_string(e.n));
  const double n = static_cast<double>(e.n);
  e.restitution = std::accumulate(ratios.begin(), ratios.end(), 0.0) / n;
  double ss = 0.0;
  for (double r : ratios) ss += (r - e.restitution) * (r - e.restitution);
  e.sd = std::sqrt(ss / (n - 1.0));
  const boost::math::students_t dist(n - 1.0);
  const double tq = boost::math::quantile(boost::math::complement(dist, 0.025));
  const double half = tq * e.sd / std::sqrt(n);
  e.ci95 = {e.restitution - half, e.restitution + half};
  e.ratios = std::move(ratios);
  return e;
}

// z ~ c0 + c1 u + c2 u^2 with u = t - t0.
struct Parabola {
  double t0 = 0.0, c0 = 0.0, c1 = 0.0, c2 = 0.0;
  double slope(double t) const { return c1 + 2.0 * c2 * (t - t0); }
};

std::optional<Parabola> fit(const std::vector<double>& t, const std::vector<double>& z, std::size_t lo, std::size_t hi) {
  if (hi < lo + 3) return std::nullopt;  // [lo, hi): at least 3 samples
  const std::size_t n = hi - lo;
  Parabola p;
  p.t0 = 0.5 * (t[lo] + t[hi - 1]);
  Eigen::MatrixXd A(static_cast<Eigen::Index>(n), 3);
  Eigen::VectorXd b(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const double u = t[lo + i] - p.t0;
    A(static_cast<Eigen::Index>(i), 0) = 1.0;
    A(static_cast<Eigen::Index>(i), 1) = u;
    A(static_cast<Eigen::Index>(i), 2) = u * u;
    b(static_cast<Eigen::Index>(i)) = z[lo + i];
  }
  const Eigen::Vector3d c = A.colPivHouseholderQr().solve(b);
  if (!c.allFinite()) return std::nullopt;
  p.c0 = c(0);
  p.c1 = c(1);
  p.c2 = c(2);
  return p;
}

// The instant near `guess` (within [lo, hi]) where the two parabolas meet; `guess` if none.
double meeting_time(const Parabola& a, const Parabola& b, double guess, double lo, double hi) {
  // Expand both in powers of t.
  auto coeffs = [](const Parabola& p) {
    return std::array<double, 3>{p.c0 - p.c1 * p.t0 + p.c2 * p.t0 * p.t0, p.c1 - 2.0 * p.c2 * p.t0, p.c2};
  };
  const auto ca = coeffs(a), cb = coeffs(b);
  const double A = ca[2] - cb[2], B = ca[1] - cb[1], C = ca[0] - cb[0];
  std::vector<double> roots;
  if (std::abs(A) < 1e-12 * (std::abs(B) + std::abs(C) + 1e-300)) {
    if (B != 0.0) roots.push_back(-C / B);
  } else {
    const double disc = B * B - 4.0 * A * C;
    if (disc >= 0.0) {
      const double s = std::sqrt(disc);
      roots.push_back((-B + s) / (2.0 * A));
      roots.push_back((-B - s) / (2.0 * A));
    }
  }
  double best = guess, best_d = INFINITY;
  for (double r : roots)
    if (r >= lo && r <= hi && std::abs(r - guess) < best_d) {
      best = r;
      best_d = std::abs(r - guess);
    }
  return best;
}

}  // namespace

RestitutionEstimate restitution_from_pairs(const std::vector<double>& v_in, const std::vector<double>& v_out) {
  if (v_in.size() != v_out.size()) throw std::invalid_argument("v_in and v_out differ in length");
  std::vector<double> ratios;
  for (std::size_t i = 0; i < v_in.size(); ++i) {
    if (!std::isfinite(v_in[i]) || !std::isfinite(v_out[i]))
      throw std::invalid_argument("pair " + std::to_string(i + 1) + ": speeds must be finite numbers");
    if (v_in[i] == 0.0) throw std::invalid_argument("pair " + std::to_string(i + 1) + ": v_in must not be 0");
    ratios.push_back(std::abs(v_out[i]) / std::abs(v_in[i]));
  }
  return estimate_from_ratios(std::move(ratios));
}

TrackFit restitution_from_track(const std::vector<double>& t, const std::vector<double>& z) {
  if (t.size() != z.size()) throw std::invalid_argument("t and z differ in length");
  const std::size_t n = t.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(z[i]))
      throw std::invalid_argument("sample " + std::to_string(i + 1) + ": t and z must be finite numbers");
    if (i > 0 && !(t[i] > t[i - 1]))
      throw std::invalid_argument("sample " + std::to_string(i + 1) + ": times must be strictly increasing");
  }
  if (n < 9) throw std::invalid_argument("a track needs at least 9 samples (two impacts, three flights)");

  std::vector<double> d(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) d[i] = (z[i + 1] - z[i]) / (t[i + 1] - t[i]);
  // In free flight consecutive slopes differ by about -g dt plus noise; an impact makes the slope
  // jump up by (1 + e) |v|. The typical change and its robust spread (median absolute deviation)
  // set the threshold; `noise_z` is the matching height noise, used to reject poor fits.
  std::vector<double> dd;
  for (std::size_t i = 1; i + 1 < n; ++i) dd.push_back(d[i] - d[i - 1]);
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double med = median(dd);
  std::vector<double> dev;
  for (double x : dd) dev.push_back(std::abs(x - med));
  const double spread = 1.4826 * median(dev);
  // The impact falls between two samples, so the slope across it is a mix: measure the jump from
  // the slope two samples before the minimum to the one after it (free flight: -3 g dt + noise of
  // sd 2 sigma_z / dt = 0.82 spread).
  const double threshold = 3.0 * std::abs(med) + 4.0 * 0.8165 * spread;
  auto jump = [&](std::size_t i) { return d[std::min(i + 1, n - 2)] - d[i >= 2 ? i - 2 : 0]; };
  std::vector<double> dts;
  for (std::size_t i = 0; i + 1 < n; ++i) dts.push_back(t[i + 1] - t[i]);
  const double noise_z = spread * median(dts) / std::sqrt(6.0);
  const double z_range = *std::max_element(z.begin(), z.end()) - *std::min_element(z.begin(), z.end());
  // Every impact happens at the floor: a local minimum counts only near the lowest height seen
  // (a die strikes on a corner, so the COM height at impact varies a little with orientation).
  const double z_min = *std::min_element(z.begin(), z.end());
  const double near_floor = z_min + 0.05 * z_range + 4.0 * noise_z;
  std::vector<std::size_t> hits;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    if (!(d[i - 1] < 0.0 && d[i] > 0.0 && jump(i) > threshold && z[i] <= near_floor)) continue;
    // Noise can make two minima within a few samples of one impact: keep the lower one.
    if (!hits.empty() && i - hits.back() <= 3) {
      const std::size_t j = hits.back();
      if (z[i] < z[j]) hits.back() = i;
      continue;
    }
    hits.push_back(i);
  }

  // Root-mean-square residual of a fit over [lo, hi).
  auto rms = [&](const Parabola& p, std::size_t lo, std::size_t hi) {
    double ss = 0.0;
    for (std::size_t i = lo; i < hi; ++i) {
      const double u = t[i] - p.t0;
      const double r = z[i] - (p.c0 + p.c1 * u + p.c2 * u * u);
      ss += r * r;
    }
    return std::sqrt(ss / static_cast<double>(hi - lo));
  };
  const double max_rms = std::max(5.0 * noise_z, 1e-6 * z_range);

  TrackFit out;
  std::vector<double> ratios;
  for (std::size_t k = 0; k < hits.size(); ++k) {
    const std::size_t i = hits[k];
    const std::size_t before_lo = k == 0 ? 0 : hits[k - 1] + 1;
    const std::size_t after_hi = k + 1 < hits.size() ? hits[k + 1] : n;
    const auto pb = fit(t, z, before_lo, i);
    const auto pa = fit(t, z, i + 1, after_hi);
    if (!pb || !pa) continue;
    // A flight that does not look like one parabola (an impact missed inside it) is not used.
    if (rms(*pb, before_lo, i) > max_rms || rms(*pa, i + 1, after_hi) > max_rms) continue;
    TrackImpact imp;
    imp.t = meeting_time(*pb, *pa, t[i], t[i - 1], t[i + 1]);
    imp.v_in = pb->slope(imp.t);
    imp.v_out = pa->slope(imp.t);
    imp.g_before = -2.0 * pb->c2;
    imp.g_after = -2.0 * pa->c2;
    if (!(imp.v_in < 0.0 && imp.v_out > 0.0)) continue;
    imp.ratio = -imp.v_out / imp.v_in;
    out.impacts.push_back(imp);
    ratios.push_back(imp.ratio);
  }
  if (ratios.size() < 2)
    throw std::invalid_argument("found " + std::to_string(ratios.size()) +
                                " usable impact(s); need at least 2 (each with 3+ samples of flight on both sides)");
  out.estimate = estimate_from_ratios(std::move(ratios));
  return out;
}

}  // namespace dicesim

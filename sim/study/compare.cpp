#include "sim/study/compare.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <boost/math/distributions/chi_squared.hpp>

namespace dicesim {

std::uint64_t FaceCounts::total() const { return std::accumulate(counts.begin(), counts.end(), std::uint64_t{0}); }

ChiSquare chi2_homogeneity(const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b,
                           double* min_expected) {
  if (a.size() != b.size()) throw std::invalid_argument("chi2_homogeneity: count vectors differ in length");
  const double na = static_cast<double>(std::accumulate(a.begin(), a.end(), std::uint64_t{0}));
  const double nb = static_cast<double>(std::accumulate(b.begin(), b.end(), std::uint64_t{0}));
  ChiSquare r;
  double min_e = std::numeric_limits<double>::infinity();
  if (na == 0.0 || nb == 0.0) {
    if (min_expected) *min_expected = 0.0;
    return r;
  }
  const double n = na + nb;
  int cells = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double col = static_cast<double>(a[i] + b[i]);
    if (col == 0.0) continue;
    ++cells;
    const double ea = na * col / n, eb = nb * col / n;
    min_e = std::min({min_e, ea, eb});
    const double da = static_cast<double>(a[i]) - ea, db = static_cast<double>(b[i]) - eb;
    r.statistic += da * da / ea + db * db / eb;
  }
  r.dof = cells - 1;
  if (r.dof > 0) {
    boost::math::chi_squared dist(r.dof);
    r.p_value = boost::math::cdf(boost::math::complement(dist, r.statistic));
  }
  if (min_expected) *min_expected = std::isfinite(min_e) ? min_e : 0.0;
  return r;
}

Interval difference_interval(std::uint64_t x_a, std::uint64_t n_a, std::uint64_t x_b, std::uint64_t n_b, double z) {
  const double pa = n_a ? static_cast<double>(x_a) / static_cast<double>(n_a) : 0.0;
  const double pb = n_b ? static_cast<double>(x_b) / static_cast<double>(n_b) : 0.0;
  const Interval a = wilson_interval(x_a, n_a, z), b = wilson_interval(x_b, n_b, z);
  const double d = pa - pb;
  const double lo = d - std::sqrt((pa - a.lo) * (pa - a.lo) + (b.hi - pb) * (b.hi - pb));
  const double hi = d + std::sqrt((a.hi - pa) * (a.hi - pa) + (pb - b.lo) * (pb - b.lo));
  return {std::max(-1.0, lo), std::min(1.0, hi)};
}

Comparison compare_counts(const FaceCounts& a, const FaceCounts& b) {
  if (a.labels.size() != a.counts.size() || b.labels.size() != b.counts.size())
    throw std::invalid_argument("compare: labels and counts differ in length");
  std::vector<int> la = a.labels, lb = b.labels;
  std::sort(la.begin(), la.end());
  std::sort(lb.begin(), lb.end());
  if (std::adjacent_find(la.begin(), la.end()) != la.end() || std::adjacent_find(lb.begin(), lb.end()) != lb.end())
    throw std::invalid_argument("compare: a face label repeats");
  if (la != lb) {
    // Say which: labels of one result that the other lacks (e.g. a d20 against a d6's counts).
    auto list = [](const std::vector<int>& v) {
      std::string s;
      for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
      return s.empty() ? std::string("none") : s;
    };
    std::vector<int> only_a, only_b;
    std::set_difference(la.begin(), la.end(), lb.begin(), lb.end(), std::back_inserter(only_a));
    std::set_difference(lb.begin(), lb.end(), la.begin(), la.end(), std::back_inserter(only_b));
    throw std::invalid_argument("compare: the two results have different face labels: missing in A: " + list(only_b) +
                                "; missing in B: " + list(only_a));
  }

  Comparison c;
  c.n_a = a.total();
  c.n_b = b.total();
  std::vector<std::uint64_t> ca, cb;
  for (int label : la) {
    const auto ia = static_cast<std::size_t>(std::find(a.labels.begin(), a.labels.end(), label) - a.labels.begin());
    const auto ib = static_cast<std::size_t>(std::find(b.labels.begin(), b.labels.end(), label) - b.labels.begin());
    FaceDifference f;
    f.label = label;
    f.count_a = a.counts[ia];
    f.count_b = b.counts[ib];
    f.p_a = c.n_a ? static_cast<double>(f.count_a) / static_cast<double>(c.n_a) : 0.0;
    f.p_b = c.n_b ? static_cast<double>(f.count_b) / static_cast<double>(c.n_b) : 0.0;
    f.diff = f.p_a - f.p_b;
    f.ci95 = difference_interval(f.count_a, c.n_a, f.count_b, c.n_b);
    c.faces.push_back(f);
    ca.push_back(f.count_a);
    cb.push_back(f.count_b);
  }
  c.chi2 = chi2_homogeneity(ca, cb, &c.min_expected);
  return c;
}

}  // namespace dicesim

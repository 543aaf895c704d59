#include "sim/study/equivalence.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include <boost/math/distributions/normal.hpp>

namespace dicesim {

namespace {

std::uint64_t sum(const std::vector<std::uint64_t>& v) { return std::accumulate(v.begin(), v.end(), std::uint64_t{0}); }

void check_alpha(double alpha) {
  if (!(alpha > 0.0 && alpha < 0.5))
    throw std::invalid_argument("equivalence: alpha " + std::to_string(alpha) + " is outside (0, 0.5)");
}

// An outcome neither run ever gave: no difference and no variance, equivalent at any margin (a
// relative margin is then 0 itself).
OutcomeEquivalence unseen(double margin) {
  OutcomeEquivalence o;
  o.margin = margin;
  o.p_lower = o.p_upper = o.tost_p = 0.0;
  return o;
}

// Fills the per-outcome tests from diff and se, and the Holm verdict.
Equivalence finish(std::vector<OutcomeEquivalence> o, double alpha, bool paired) {
  Equivalence e;
  e.alpha = alpha;
  e.paired = paired;
  std::vector<double> p;
  for (const OutcomeEquivalence& x : o) p.push_back(x.tost_p);
  const std::vector<double> adj = holm_adjust(p);
  e.equivalent = !o.empty();
  for (std::size_t i = 0; i < o.size(); ++i) {
    o[i].holm_p = adj[i];
    o[i].equivalent = adj[i] <= alpha;
    e.equivalent = e.equivalent && o[i].equivalent;
  }
  e.outcomes = std::move(o);
  return e;
}

}  // namespace

OutcomeEquivalence tost(double diff, double se, double margin, double alpha) {
  if (!(margin > 0.0)) throw std::invalid_argument("equivalence: margin " + std::to_string(margin) + " is not > 0");
  OutcomeEquivalence o;
  o.diff = diff;
  o.se = se;
  o.margin = margin;
  if (se > 0.0) {
    const boost::math::normal z;
    o.p_lower = boost::math::cdf(boost::math::complement(z, (diff + margin) / se));
    o.p_upper = boost::math::cdf(z, (diff - margin) / se);
    const double q = boost::math::quantile(boost::math::complement(z, alpha));
    o.ci = {diff - q * se, diff + q * se};
  } else {  // no variance: the difference is what it is
    o.p_lower = diff > -margin ? 0.0 : 1.0;
    o.p_upper = diff < margin ? 0.0 : 1.0;
    o.ci = {diff, diff};
  }
  o.tost_p = std::max(o.p_lower, o.p_upper);
  return o;
}

std::vector<double> holm_adjust(const std::vector<double>& p) {
  const std::size_t k = p.size();
  std::vector<std::size_t> order(k);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return p[i] < p[j]; });
  std::vector<double> adj(k, 1.0);
  double running = 0.0;
  for (std::size_t r = 0; r < k; ++r) {
    running = std::max(running, std::min(1.0, static_cast<double>(k - r) * p[order[r]]));
    adj[order[r]] = running;
  }
  return adj;
}

Equivalence equivalence_unpaired(const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b,
                                 const Margin& margin, double alpha) {
  check_alpha(alpha);
  if (a.size() != b.size()) throw std::invalid_argument("equivalence: the count vectors differ in length");
  const std::uint64_t na = sum(a), nb = sum(b);
  if (na == 0 || nb == 0) throw std::invalid_argument("equivalence: a run has no tosses");
  std::vector<OutcomeEquivalence> out;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double pa = static_cast<double>(a[i]) / static_cast<double>(na);
    const double pb = static_cast<double>(b[i]) / static_cast<double>(nb);
    const double pooled = static_cast<double>(a[i] + b[i]) / static_cast<double>(na + nb);
    const double se = std::sqrt(pa * (1.0 - pa) / static_cast<double>(na) + pb * (1.0 - pb) / static_cast<double>(nb));
    OutcomeEquivalence o = a[i] + b[i] == 0 ? unseen(margin(0.0)) : tost(pa - pb, se, margin(pooled), alpha);
    o.p_a = pa;
    o.p_b = pb;
    out.push_back(o);
  }
  return finish(std::move(out), alpha, false);
}

PairedCounts paired_counts(const std::vector<std::int16_t>& a, const std::vector<std::int16_t>& b, int outcomes) {
  if (a.size() != b.size())
    throw std::invalid_argument("paired outcomes: the runs have " + std::to_string(a.size()) + " and " +
                                std::to_string(b.size()) + " tosses (pairs need the same toss indices)");
  const auto k = static_cast<std::size_t>(outcomes);
  PairedCounts p{std::vector<std::uint64_t>(k, 0), std::vector<std::uint64_t>(k, 0), std::vector<std::uint64_t>(k, 0),
                 std::vector<std::uint64_t>(k, 0), 0, 0};
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] < -1 || a[i] >= outcomes || b[i] < -1 || b[i] >= outcomes)
      throw std::invalid_argument("paired outcomes: toss " + std::to_string(i) + " has an outcome outside [-1, " +
                                  std::to_string(outcomes) + ")");
    if (a[i] < 0 || b[i] < 0) {
      ++p.dropped;
      continue;
    }
    const auto ia = static_cast<std::size_t>(a[i]), ib = static_cast<std::size_t>(b[i]);
    ++p.pairs;
    ++p.a[ia];
    ++p.b[ib];
    if (ia != ib) {
      ++p.a_only[ia];
      ++p.b_only[ib];
    }
  }
  return p;
}

Equivalence equivalence_paired(const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b,
                               const std::vector<std::uint64_t>& a_only, const std::vector<std::uint64_t>& b_only,
                               const Margin& margin, double alpha) {
  check_alpha(alpha);
  const std::size_t k = a.size();
  if (b.size() != k || a_only.size() != k || b_only.size() != k)
    throw std::invalid_argument("equivalence: the count vectors differ in length");
  const std::uint64_t n = sum(a);
  if (n == 0) throw std::invalid_argument("equivalence: a run has no tosses");
  if (sum(b) != n) throw std::invalid_argument("equivalence: paired runs must have the same number of tosses");
  const double dn = static_cast<double>(n);
  std::vector<OutcomeEquivalence> out;
  for (std::size_t i = 0; i < k; ++i) {
    // a[i] - b[i] = a_only[i] - b_only[i]: the concordant tosses cancel.
    if (a[i] + b_only[i] != b[i] + a_only[i] || a_only[i] > a[i] || b_only[i] > b[i])
      throw std::invalid_argument("equivalence: outcome " + std::to_string(i) + "'s discordant counts do not fit its counts");
    const double pa = static_cast<double>(a[i]) / dn, pb = static_cast<double>(b[i]) / dn;
    const double d = pa - pb;
    const double var = std::max(0.0, static_cast<double>(a_only[i] + b_only[i]) / dn - d * d);
    OutcomeEquivalence o =
        a[i] + b[i] == 0 ? unseen(margin(0.0)) : tost(d, std::sqrt(var / dn), margin(0.5 * (pa + pb)), alpha);
    o.p_a = pa;
    o.p_b = pb;
    out.push_back(o);
  }
  return finish(std::move(out), alpha, true);
}

}  // namespace dicesim

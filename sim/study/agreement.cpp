#include "sim/study/agreement.hpp"

#include <cmath>
#include <stdexcept>

#include <boost/math/distributions/chi_squared.hpp>

#include "sim/math.hpp"

namespace dicesim {

Agreement agreement_of(std::span<const std::uint64_t> a, std::span<const std::uint64_t> b) {
  if (a.size() != b.size()) throw std::invalid_argument("agreement_of: different numbers of outcomes");
  const std::size_t n = a.size();
  Agreement out;
  double na = 0.0, nb = 0.0;
  for (std::size_t f = 0; f < n; ++f) {
    na += static_cast<double>(a[f]);
    nb += static_cast<double>(b[f]);
  }
  if (na == 0.0 || nb == 0.0) return out;
  int cells = 0;
  for (std::size_t f = 0; f < n; ++f) {
    const double pa = a[f] / na, pb = b[f] / nb;
    out.tv += 0.5 * std::abs(pa - pb);
    const double col = static_cast<double>(a[f] + b[f]);
    if (col == 0.0) continue;
    ++cells;
    const double p = col / (na + nb);
    // E|pa - pb| for a normal difference with variance p(1-p)(1/na + 1/nb).
    out.tv_noise += 0.5 * std::sqrt(2.0 / kPi * p * (1.0 - p) * (1.0 / na + 1.0 / nb));
    const double ea = p * na, eb = p * nb;
    out.chi2 += (a[f] - ea) * (a[f] - ea) / ea + (b[f] - eb) * (b[f] - eb) / eb;
  }
  out.dof = cells - 1;
  if (out.dof > 0) {
    const boost::math::chi_squared_distribution<double> d(out.dof);
    out.chi2_p = boost::math::cdf(boost::math::complement(d, out.chi2));
  }
  return out;
}

}  // namespace dicesim

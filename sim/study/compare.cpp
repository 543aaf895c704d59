#include "sim/study/compare.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <cmath>
#include <iterator>
#include <string>
#include <limits>
#include <numeric>
#include <stdexcept>

#include <boost/math/distributions/chi_squared.hpp>
#include <nlohmann/json.hpp>

#include "sim/scene/scene_error.hpp"

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

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  const auto e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

}  // namespace

FaceCounts read_face_counts(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path, "", "", "cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  FaceCounts fc;
  const std::string t = trim(text);
  if (!t.empty() && t[0] == '{') {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(t);
    } catch (const std::exception& e) {
      throw SceneError(path, "", "", std::string("not valid JSON: ") + e.what());
    }
    if (!j.contains("faces") || !j["faces"].is_array())
      throw SceneError(path, "faces", "", "missing: expected the output of `dicesim toss --json`");
    for (const auto& f : j["faces"]) {
      if (!f.contains("face") || !f["face"].is_number_integer() || !f.contains("count") || !f["count"].is_number_unsigned())
        throw SceneError(path, "faces[]", f.dump(), "each face needs an integer 'face' and a count >= 0");
      fc.labels.push_back(f["face"].get<int>());
      fc.counts.push_back(f["count"].get<std::uint64_t>());
    }
  } else {
    std::istringstream lines(text);
    std::string line;
    int line_no = 0;
    bool first = true;
    while (std::getline(lines, line)) {
      ++line_no;
      const std::string l = trim(line);
      if (l.empty() || l[0] == '#') continue;
      const auto comma = l.find(',');
      if (comma == std::string::npos || l.find(',', comma + 1) != std::string::npos)
        throw SceneError(path, "line " + std::to_string(line_no), "'" + l + "'", "expected two columns: face,count");
      const std::string a = trim(l.substr(0, comma)), b = trim(l.substr(comma + 1));
      char* ea = nullptr;
      char* eb = nullptr;
      const long face = std::strtol(a.c_str(), &ea, 10);
      const double count = std::strtod(b.c_str(), &eb);
      const bool numeric = !a.empty() && !b.empty() && *ea == '\0' && *eb == '\0';
      if (!numeric && first) {  // the header
        first = false;
        continue;
      }
      first = false;
      if (!numeric || face < 0 || face > 999 || !(count >= 0) || count != std::floor(count) || count > 1e15)
        throw SceneError(path, "line " + std::to_string(line_no), "'" + l + "'",
                         "expected face (a label, an integer in [0, 999]) and count (an integer >= 0)");
      fc.labels.push_back(static_cast<int>(face));
      fc.counts.push_back(static_cast<std::uint64_t>(count));
    }
  }
  if (fc.labels.size() < 2) throw SceneError(path, "", "", "needs the counts of at least 2 faces");
  if (fc.total() == 0) throw SceneError(path, "", "", "all counts are 0");
  return fc;
}

std::vector<int> read_toss_outcomes(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneError(path, "", "", "cannot open file");
  std::vector<int> out;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string l = trim(line);
    if (l.empty() || l[0] == '#') continue;
    char* end = nullptr;
    const long v = std::strtol(l.c_str(), &end, 10);
    if (*end != '\0' || v < -1 || v > 999)
      throw SceneError(path, "line " + std::to_string(line_no), "'" + l + "'",
                       "expected one outcome label per toss (an integer in [0, 999], or -1: not settled); "
                       "the output of `dicesim toss --outcomes`");
    out.push_back(static_cast<int>(v));
  }
  if (out.empty()) throw SceneError(path, "", "", "no tosses: expected the output of `dicesim toss --outcomes`");
  return out;
}

}  // namespace dicesim

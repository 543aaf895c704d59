#include "messages/wire.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <string_view>

namespace dicesim::wire {

namespace {

// LCM 1.3.1's tcpq provider takes the hub's address as a dotted IPv4 only: a host name (a
// Kubernetes Service, a cluster node) is not looked up, and every connect is refused. So the name
// is looked up here (IPv4, as the provider connects), once, when the URL is resolved.
std::string with_tcpq_address(const std::string& url) {
  constexpr std::string_view kScheme = "tcpq://";
  if (url.rfind(kScheme, 0) != 0) return url;
  const std::size_t host_at = kScheme.size();
  const std::size_t host_end = url.find_first_of(":/?", host_at);
  const std::string host = url.substr(host_at, host_end == std::string::npos ? std::string::npos : host_end - host_at);
  in_addr numeric{};
  if (host.empty() || ::inet_pton(AF_INET, host.c_str(), &numeric) == 1) return url;
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  if (::getaddrinfo(host.c_str(), nullptr, &hints, &found) != 0 || !found) return url;  // LCM says it cannot connect
  char text[INET_ADDRSTRLEN] = {};
  ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(found->ai_addr)->sin_addr, text, sizeof text);
  ::freeaddrinfo(found);
  return std::string(kScheme) + text + (host_end == std::string::npos ? "" : url.substr(host_end));
}

std::string chosen_url(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) return env;
  return kDefaultUrl;
}

}  // namespace

std::string resolve_url(const std::string& flag) { return with_tcpq_address(chosen_url(flag)); }

std::int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

namespace {

// Reads an LCM encoding (big-endian) without trusting it: every step checks the bytes left.
class Walker {
 public:
  Walker(const void* d, std::size_t n) : p_(static_cast<const std::uint8_t*>(d)), n_(n) {}
  bool skip(std::size_t k) {
    if (k > n_ - pos_) return false;
    pos_ += k;
    return true;
  }
  bool i32(std::int32_t& v) {
    if (4 > n_ - pos_) return false;
    const std::uint32_t u = (std::uint32_t{p_[pos_]} << 24) | (std::uint32_t{p_[pos_ + 1]} << 16) |
                            (std::uint32_t{p_[pos_ + 2]} << 8) | std::uint32_t{p_[pos_ + 3]};
    std::memcpy(&v, &u, 4);
    pos_ += 4;
    return true;
  }
  // A string: int32 length including the terminating NUL (>= 1), then the bytes.
  bool str() {
    std::int32_t len;
    return i32(len) && len >= 1 && skip(static_cast<std::size_t>(len));
  }
  // A count for an array of elements of at least `min_size` bytes each.
  bool count(std::int32_t& c, std::size_t min_size) {
    return i32(c) && c >= 0 && static_cast<std::size_t>(c) * min_size <= n_ - pos_;
  }
  bool at_end() const { return pos_ == n_; }

 private:
  const std::uint8_t* p_;
  std::size_t n_, pos_ = 0;
};

}  // namespace

bool plausible_run_start(const void* data, std::size_t len) {
  Walker w(data, len);
  std::int32_t n = 0;
  if (!w.skip(8 + 8 + 8) || !w.str() || !w.str() || !w.str()) return false;  // hash utime run_id origin path text
  if (!w.count(n, 5)) return false;
  for (int pass = 0; pass < 2; ++pass)
    for (std::int32_t i = 0; i < n; ++i)
      if (!w.str()) return false;
  if (!w.count(n, 5)) return false;
  for (std::int32_t i = 0; i < n; ++i)
    if (!w.str()) return false;
  // hash fingerprint fidelity seed total trace_every; then the outcomes and the assets
  if (!w.str() || !w.skip(8) || !w.str() || !w.skip(8 + 8 + 4)) return false;
  if (!w.count(n, 4) || n < 1 || n > kMaxOutcomes || !w.skip(static_cast<std::size_t>(n) * 4)) return false;
  if (!w.count(n, 10)) return false;
  for (int pass = 0; pass < 2; ++pass)
    for (std::int32_t i = 0; i < n; ++i)
      if (!w.str()) return false;
  return w.at_end();
}

bool plausible_probabilities(const void* data, std::size_t len) {
  Walker w(data, len);
  std::int32_t n = 0;
  // hash utime run_id; n labels (4) + counts p ci_lo ci_hi (8 each); then 173 bytes of scalars
  // (nine corrections of 8 bytes among them), then the provenance string
  return w.skip(8 + 8 + 8) && w.count(n, 36) && n >= 1 && n <= kMaxOutcomes && w.skip(static_cast<std::size_t>(n) * 36) &&
         w.skip(173) && w.str() && w.at_end();
}

bool valid_outcome_labels(const std::vector<std::int32_t>& labels) {
  if (labels.empty() || labels.size() > static_cast<std::size_t>(kMaxOutcomes)) return false;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (labels[i] < 0 || labels[i] > kMaxLabel || (i > 0 && labels[i] <= labels[i - 1])) return false;
  return true;
}

const char* legacy_format(const void* data, std::size_t len) {
  if (len < 8) return nullptr;
  std::uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | static_cast<const std::uint8_t*>(data)[i];
  // lcm-gen's hashes of the six-outcome types (dicesim before the wire carried N outcomes).
  switch (h) {
    case 0x16854fcd47c16d6eULL: return "run_start of the six-outcome wire (no outcome labels)";
    case 0x5196dd2e391cfd23ULL: return "toss_batch of the six-outcome wire (faces 1..6)";
    case 0xefc6a3d437de62eaULL: return "probabilities of the six-outcome wire ([6] arrays)";
    // ... and of the wire whose corrections had four kinds (before the sustained phase's guards).
    case 0xa777923107885cfeULL: return "toss_batch of the four-corrections wire";
    case 0x763722945abe8778ULL: return "probabilities of the four-corrections wire (corrections[4])";
    // ... and the answer before it carried its provenance.
    case 0x763722945aa34978ULL: return "probabilities of the wire without provenance";
    default: return nullptr;
  }
}

bool plausible_toss_batch(const void* data, std::size_t len) {
  Walker w(data, len);
  std::int32_t n = 0;
  std::int32_t corrected = 0;  // tosses with corrections: offset and nine counts, 40 bytes each
  return w.skip(8 + 5 * 8) && w.count(n, 6) && n <= kMaxBatch && w.skip(static_cast<std::size_t>(n) * 6) &&
         w.count(corrected, 40) && corrected <= n && w.skip(static_cast<std::size_t>(corrected) * 40) && w.at_end();
}

bool plausible_worker_status(const void* data, std::size_t len) {
  Walker w(data, len);
  std::int32_t n = 0;
  return w.skip(8 + 3 * 8 + 4) && w.str() && w.skip(1) && w.str() && w.count(n, 8) &&
         w.skip(static_cast<std::size_t>(n) * 8) && w.skip(8 + 8 + 8 + 8) && w.at_end();
}

}  // namespace dicesim::wire

// The wire contract in C++: channel names, and encode/decode of the lcm-gen types that never
// trust the bytes (truncated, garbage or hostile payloads are reported, never crash).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "dicesim_lcm/bounce_state.hpp"
#include "dicesim_lcm/probabilities.hpp"
#include "dicesim_lcm/run_start.hpp"
#include "dicesim_lcm/toss_batch.hpp"
#include "dicesim_lcm/work_lease.hpp"
#include "dicesim_lcm/worker_status.hpp"

namespace dicesim::wire {

// One prefix for every channel, so `lcm-logger -c 'DICESIM_.*'` records exactly dicesim.
inline constexpr const char* kRunStart = "DICESIM_RUN_START";
inline constexpr const char* kWorkLease = "DICESIM_WORK_LEASE";
inline constexpr const char* kTossBatch = "DICESIM_TOSS_BATCH";
inline constexpr const char* kBounceState = "DICESIM_BOUNCE_STATE";
inline constexpr const char* kWorkerStatus = "DICESIM_WORKER_STATUS";
inline constexpr const char* kProbabilities = "DICESIM_PROBABILITIES";

// Host-confined (TTL 0: multicast never leaves this machine) when neither --lcm nor
// LCM_DEFAULT_URL says otherwise.
inline constexpr const char* kDefaultUrl = "udpm://239.255.76.67:7667?ttl=0";
// --lcm URL, else $LCM_DEFAULT_URL, else kDefaultUrl. A tcpq://HOST:PORT's HOST given by name is
// looked up (IPv4) and replaced by its address: LCM 1.3.1's tcpq provider connects to dotted
// addresses only (a name, e.g. a Kubernetes Service's, was refused on every connect).
std::string resolve_url(const std::string& flag);

// A toss_batch carries at most kMaxBatch tosses: 6 bytes each, ~48 KB, one LCM datagram (under
// 64 KB). A worker publishes kDefaultBatch (~12 KB) unless told otherwise: on a LAN a datagram is
// cut into 1500-byte IP fragments and one lost fragment loses it; `dicesim run` on its
// host-confined URL (nothing leaves the machine, loopback MTU 64 KB) uses kMaxBatch.
inline constexpr int kMaxBatch = 8192;
inline constexpr int kDefaultBatch = 2048;

// A die's outcomes on the wire (run_start, probabilities): 1 to kMaxOutcomes labels, ascending,
// each in [0, kMaxLabel]. A toss result is an index into them (int8: kMaxOutcomes must stay < 128).
// A message that claims more is not decoded (rejected and counted by its receiver).
inline constexpr int kMaxOutcomes = 120;
inline constexpr int kMaxLabel = 999;
static_assert(kMaxOutcomes < 128, "toss_batch.outcomes is int8");
// Are these labels a valid outcome list (count, range, strictly ascending)?
bool valid_outcome_labels(const std::vector<std::int32_t>& labels);

// Messages recorded before a die could have any number of outcomes (toss_batch faces 1..6,
// fixed [6] arrays in probabilities, run_start without outcome labels), or before the corrections
// had nine kinds (toss_batch and probabilities with four), have other LCM type hashes and never
// decode as today's types. Names the old type if `data` is one, else nullptr.
const char* legacy_format(const void* data, std::size_t len);

// Counted arrays in lcm-gen's decoders are resized before their bytes are checked, so a hostile
// count could allocate gigabytes. These walk the encoding first and accept only payloads whose
// every count and length fits inside the bytes given.
bool plausible_run_start(const void* data, std::size_t len);
bool plausible_toss_batch(const void* data, std::size_t len);
bool plausible_worker_status(const void* data, std::size_t len);
bool plausible_probabilities(const void* data, std::size_t len);

template <class T>
bool plausible(const void*, std::size_t) {
  return true;  // fixed-size types: decode() checks the length itself
}
template <>
inline bool plausible<dicesim_lcm::run_start>(const void* d, std::size_t n) { return plausible_run_start(d, n); }
template <>
inline bool plausible<dicesim_lcm::toss_batch>(const void* d, std::size_t n) { return plausible_toss_batch(d, n); }
template <>
inline bool plausible<dicesim_lcm::probabilities>(const void* d, std::size_t n) {
  return plausible_probabilities(d, n);
}
template <>
inline bool plausible<dicesim_lcm::worker_status>(const void* d, std::size_t n) {
  return plausible_worker_status(d, n);
}

// The message, or nothing if the bytes are not exactly one valid encoding of T.
template <class T>
std::optional<T> decode(const void* data, std::size_t len) {
  if (len > (1u << 26) || !plausible<T>(data, len)) return std::nullopt;
  T msg;
  try {
    if (msg.decode(data, 0, static_cast<int>(len)) != static_cast<int>(len)) return std::nullopt;
  } catch (const std::exception&) {  // e.g. a zero string length: lcm-gen's assign() throws
    return std::nullopt;
  }
  return msg;
}

template <class T>
std::vector<std::uint8_t> encode(const T& msg) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

std::int64_t now_utime();  // microseconds since the epoch (message timestamps only)

}  // namespace dicesim::wire

// The LCM -> DDS bridge: listens to a dicesim LCM bus (run_start, worker_status,
// probabilities) and republishes every answer on `dicesim_probabilities` at once and what it
// knows of each run on `dicesim_run_status`. Runs come and go (aggregators restart, new runs
// get new ids); the bridge keeps going until it is told to stop.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "bridge/run_table.hpp"

namespace dicesim::bridge {

struct BridgeDef {
  std::string lcm_url;                   // already resolved (wire::resolve_url)
  std::string dds_config;                // a Cyclone configuration URI (resolve_dds_config)
  std::uint32_t dds_domain = 0;
  const std::atomic<bool>* stop = nullptr;  // set from a signal handler: leave within ~50 ms
  RunTableDef runs = default_run_table_def();
  // The run key (messages/auth.hpp): only messages whose HMAC seal opens are forwarded to DDS; the
  // rest are dropped and counted (BridgeStats::unauthenticated). Empty: no authentication.
  std::vector<std::uint8_t> key;
};
BridgeDef default_bridge_def();

struct BridgeStats {
  std::int64_t answers = 0;       // probabilities forwarded
  std::int64_t statuses = 0;      // run_status samples written
  std::int64_t runs = 0;          // distinct runs seen
  std::int64_t malformed = 0;     // LCM messages that did not decode (ignored)
  std::int64_t write_errors = 0;  // dds_write failures
  std::int64_t unauthenticated = 0;  // with a key: messages that failed the HMAC check (ignored)
};

// Blocks until *def.stop. Throws std::runtime_error if LCM or DDS cannot be set up.
BridgeStats run_bridge(const BridgeDef& def);

}  // namespace dicesim::bridge

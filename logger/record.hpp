// Recording a live run: every message on the DICESIM_ channels, as received, into an LCM event
// log (the file the stock lcm-logger writes; lcm-logplayer plays it back).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace dicesim::eventlog {

struct RecordOptions {
  std::string url;                            // resolved (wire::resolve_url)
  std::string path;                           // the log to write (truncated)
  std::string channels = "DICESIM_.*";        // LCM channel regex
  bool until_done = false;                    // stop when the run's final probabilities arrive
  std::int64_t run_id = 0;                    // the run to wait for (0: the first one heard)
  double timeout_s = 0.0;                     // > 0: stop after this long
  double linger_s = 0.3;                      // after the final result: the other copies, last heartbeats
  const std::atomic<bool>* cancel = nullptr;  // set from a signal handler: stop now
  std::function<void()> on_ready;             // subscribed: messages from now on are recorded
  // The run key (messages/auth.hpp): every message is still written as received (sealed, and
  // forgeries too: `replay --key-file` drops them again), but only authentic ones are looked at
  // to learn the run and its end. Empty: no authentication.
  std::vector<std::uint8_t> key;
};
RecordOptions default_record_options();

enum class RecordEnd { Done, Stopped, TimedOut, Failed };

struct RecordResult {
  RecordEnd end = RecordEnd::Failed;
  std::string error;
  std::uint64_t events = 0, bytes = 0;
  std::vector<std::int64_t> runs;  // run ids announced, in order heard
  std::int64_t done_run = 0;       // the run whose final result ended the recording
  std::uint64_t unauthenticated = 0;  // with a key: run_start / probabilities that failed the HMAC check
  double elapsed_s = 0.0;
};

// Throws LogError if the file cannot be created; LCM trouble is a Failed result.
RecordResult record(const RecordOptions& opt);

}  // namespace dicesim::eventlog

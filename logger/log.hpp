// Logging for every dicesim process: spdlog's default logger, configured once, so that any code
// logs with plain spdlog::info / warn / debug. Every line names the process's component, run id
// and worker id (a small thread-safe context, read when a line is formatted). Lines go to stderr
// (stdout carries tables and JSON that scripts parse); --log-file adds one JSON object per line.
// Never log in the per-step hot path (sim/ flight and contact code).
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace dicesim::logging {

enum class Level { trace, debug, info, warn, error, critical, off };

// "trace, debug, info, warn, error, critical, off": what --log-level and DICESIM_LOG_LEVEL accept.
inline constexpr const char* kLevelNames = "trace, debug, info, warn, error, critical, off";
inline constexpr const char* kLevelEnv = "DICESIM_LOG_LEVEL";
inline constexpr const char* kFileEnv = "DICESIM_LOG_FILE";  // how `dicesim run` passes --log-file to its workers

// Exactly one of the names above (case-insensitive), else nothing.
std::optional<Level> parse_level(std::string_view name);
const char* level_name(Level level);

// A level name nobody accepts, from the flag or from the environment: bad input (exit 2).
struct BadLevel : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

struct LogOptions {
  std::string level;      // flag value; empty: $DICESIM_LOG_LEVEL, else info
  std::string file;       // JSON lines appended here; empty: $DICESIM_LOG_FILE, else none
  std::string component;  // e.g. "worker"; empty: keep the current one
  bool use_env = true;    // read the two environment variables above (tests turn it off)
};
LogOptions default_log_options();

// The level in force: the flag if given, else the environment, else info. Throws BadLevel
// naming the source (--log-level or DICESIM_LOG_LEVEL), the value and kLevelNames.
Level resolve_level(const std::string& flag, const char* env);

// Replaces spdlog's default logger: stderr, plus the JSON-lines file if any. Throws BadLevel,
// or std::runtime_error when the file cannot be opened. Call again to reconfigure.
void init(const LogOptions& opt);
Level current_level();
std::string current_file();  // "" when none

// Sets DICESIM_LOG_LEVEL and DICESIM_LOG_FILE to what is in force, for child processes.
void export_to_children();

// The context printed on every line. Thread-safe; 0 means "none" for the ids.
void set_component(std::string_view component);
void set_run_id(std::int64_t run_id);
void set_worker_id(std::int64_t worker_id);
std::string component();
std::int64_t run_id();
std::int64_t worker_id();

// Flushes every sink (lines are already written through one by one; for callers about to exit).
void flush();

}  // namespace dicesim::logging

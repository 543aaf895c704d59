#include "logger/log.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <mutex>
#include <vector>

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/stdout_sinks.h>  // also the stderr sinks
#include <spdlog/spdlog.h>

namespace dicesim::logging {
namespace {

constexpr const char* kNames[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};

// The context. Ids are atomics (read on every line, from any thread); the component is a short
// string behind a mutex: it changes once or twice per process.
std::atomic<std::int64_t> g_run{0}, g_worker{0};
std::mutex g_mutex;
std::string g_component = "dicesim";  // guarded by g_mutex
Level g_level = Level::info;           // guarded by g_mutex
std::string g_file;                    // guarded by g_mutex

spdlog::level::level_enum to_spdlog(Level l) {
  switch (l) {
    case Level::trace: return spdlog::level::trace;
    case Level::debug: return spdlog::level::debug;
    case Level::info: return spdlog::level::info;
    case Level::warn: return spdlog::level::warn;
    case Level::error: return spdlog::level::err;
    case Level::critical: return spdlog::level::critical;
    case Level::off: break;
  }
  return spdlog::level::off;
}

void append(spdlog::memory_buf_t& dest, std::string_view s) { dest.append(s.data(), s.data() + s.size()); }

void append_id(spdlog::memory_buf_t& dest, std::int64_t id) {
  if (id == 0) return append(dest, "-");
  append(dest, std::to_string(id));
}

// "component run=R worker=W" (ids "-" when none): the %* flag of the stderr pattern.
class ContextFlag final : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg&, const std::tm&, spdlog::memory_buf_t& dest) override {
    append(dest, component());
    append(dest, " run=");
    append_id(dest, g_run.load(std::memory_order_relaxed));
    append(dest, " worker=");
    append_id(dest, g_worker.load(std::memory_order_relaxed));
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<ContextFlag>(); }
};

void append_json_string(spdlog::memory_buf_t& dest, std::string_view s) {
  dest.push_back('"');
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      dest.push_back('\\');
      dest.push_back(c);
    } else if (c == '\n') {
      append(dest, "\\n");
    } else if (c == '\t') {
      append(dest, "\\t");
    } else if (u < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", u);
      append(dest, buf);
    } else {
      dest.push_back(c);
    }
  }
  dest.push_back('"');
}

// Run and worker ids are 63-bit: written as strings, because many JSON readers hold numbers as
// doubles (exact only to 2^53). null when none.
void append_json_id(spdlog::memory_buf_t& dest, std::int64_t id) {
  if (id == 0) return append(dest, "null");
  dest.push_back('"');
  append(dest, std::to_string(id));
  dest.push_back('"');
}

const char* json_level(spdlog::level::level_enum l) {
  switch (l) {
    case spdlog::level::trace: return "trace";
    case spdlog::level::debug: return "debug";
    case spdlog::level::info: return "info";
    case spdlog::level::warn: return "warn";
    case spdlog::level::err: return "error";
    case spdlog::level::critical: return "critical";
    default: return "off";
  }
}

// One JSON object per line: {"ts","level","component","run","worker","msg"}; ts in UTC, ISO 8601.
class JsonLineFormatter final : public spdlog::formatter {
 public:
  void format(const spdlog::details::log_msg& msg, spdlog::memory_buf_t& dest) override {
    const auto since_epoch = msg.time.time_since_epoch();
    const auto secs = std::chrono::duration_cast<std::chrono::seconds>(since_epoch);
    const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(since_epoch - secs).count();
    const std::time_t t = static_cast<std::time_t>(secs.count());
    std::tm tm{};
    gmtime_r(&t, &tm);
    char ts[64];  // room for any int values: no truncation warning
    std::snprintf(ts, sizeof ts, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                  tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
    append(dest, "{\"ts\":\"");
    append(dest, ts);
    append(dest, "\",\"level\":\"");
    append(dest, json_level(msg.level));  // the names --log-level takes ("warn", not spdlog's "warning")
    append(dest, "\",\"component\":");
    append_json_string(dest, component());
    append(dest, ",\"run\":");
    append_json_id(dest, g_run.load(std::memory_order_relaxed));
    append(dest, ",\"worker\":");
    append_json_id(dest, g_worker.load(std::memory_order_relaxed));
    append(dest, ",\"msg\":");
    append_json_string(dest, std::string_view(msg.payload.data(), msg.payload.size()));
    append(dest, "}\n");
  }
  std::unique_ptr<spdlog::formatter> clone() const override { return std::make_unique<JsonLineFormatter>(); }
};

}  // namespace

std::optional<Level> parse_level(std::string_view name) {
  for (int i = 0; i < 7; ++i) {
    const std::string_view n = kNames[i];
    if (n.size() != name.size()) continue;
    bool same = true;
    for (std::size_t k = 0; k < n.size() && same; ++k)
      same = n[k] == static_cast<char>(name[k] | 0x20);  // ASCII lower case
    if (same) return static_cast<Level>(i);
  }
  return std::nullopt;
}

const char* level_name(Level level) { return kNames[static_cast<int>(level)]; }

LogOptions default_log_options() { return LogOptions{}; }

Level resolve_level(const std::string& flag, const char* env) {
  if (!flag.empty()) {
    if (auto l = parse_level(flag)) return *l;
    throw BadLevel("--log-level '" + flag + "' is not a level; allowed: " + kLevelNames);
  }
  if (env && *env) {
    if (auto l = parse_level(env)) return *l;
    throw BadLevel(std::string(kLevelEnv) + "='" + env + "' is not a level; allowed: " + kLevelNames);
  }
  return Level::info;
}

void init(const LogOptions& opt) {
  const Level level = resolve_level(opt.level, opt.use_env ? std::getenv(kLevelEnv) : nullptr);
  std::string file = opt.file;
  if (file.empty() && opt.use_env)
    if (const char* f = std::getenv(kFileEnv)) file = f;
  if (!opt.component.empty()) set_component(opt.component);

  std::vector<spdlog::sink_ptr> sinks;
  auto err = std::make_shared<spdlog::sinks::stderr_sink_mt>();
  auto pattern = std::make_unique<spdlog::pattern_formatter>(spdlog::pattern_time_type::utc);
  pattern->add_flag<ContextFlag>('*').set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%l] [%*] %v");
  err->set_formatter(std::move(pattern));
  sinks.push_back(err);
  if (!file.empty()) {
    std::shared_ptr<spdlog::sinks::basic_file_sink_mt> json;
    try {
      json = std::make_shared<spdlog::sinks::basic_file_sink_mt>(file, false);  // append: workers share it
    } catch (const spdlog::spdlog_ex& e) {
      throw std::runtime_error("cannot open log file '" + file + "': " + e.what());
    }
    json->set_formatter(std::make_unique<JsonLineFormatter>());
    sinks.push_back(json);
  }
  auto logger = std::make_shared<spdlog::logger>("dicesim", sinks.begin(), sinks.end());
  logger->set_level(to_spdlog(level));
  // Each line is written through at once: processes that share one file (a run and its workers)
  // then append whole lines, and nothing is lost when a process is killed.
  logger->flush_on(spdlog::level::trace);
  spdlog::set_default_logger(logger);
  std::lock_guard<std::mutex> lock(g_mutex);
  g_level = level;
  g_file = file;
}

Level current_level() {
  std::lock_guard<std::mutex> lock(g_mutex);
  return g_level;
}

std::string current_file() {
  std::lock_guard<std::mutex> lock(g_mutex);
  return g_file;
}

void export_to_children() {
  std::lock_guard<std::mutex> lock(g_mutex);
  setenv(kLevelEnv, level_name(g_level), 1);
  if (g_file.empty()) unsetenv(kFileEnv);
  else setenv(kFileEnv, g_file.c_str(), 1);
}

void set_component(std::string_view c) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_component.assign(c);
}
void set_run_id(std::int64_t id) { g_run.store(id, std::memory_order_relaxed); }
void set_worker_id(std::int64_t id) { g_worker.store(id, std::memory_order_relaxed); }

std::string component() {
  std::lock_guard<std::mutex> lock(g_mutex);
  return g_component;
}
std::int64_t run_id() { return g_run.load(std::memory_order_relaxed); }
std::int64_t worker_id() { return g_worker.load(std::memory_order_relaxed); }

void flush() { spdlog::default_logger()->flush(); }

}  // namespace dicesim::logging

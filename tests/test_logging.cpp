// Logging (logger/log.hpp): level names, flag-over-environment precedence, the JSON-lines file
// with component / run / worker on every line, and the command line's handling of bad levels.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "cli_runner.hpp"
#include "logger/log.hpp"

namespace lg = dicesim::logging;
using dicesim::testing::run_dicesim;
using dicesim::testing::unique_temp;

namespace {

std::vector<nlohmann::json> read_json_lines(const std::string& path) {
  std::ifstream in(path);
  std::vector<nlohmann::json> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(nlohmann::json::parse(line));  // throws on a broken line
  return lines;
}

// Leaves the process's logging as it found it (tests in one binary share spdlog's default logger).
struct RestoreLogging {
  ~RestoreLogging() {
    lg::LogOptions o = lg::default_log_options();
    o.use_env = false;
    o.component = "dicesim";
    lg::init(o);
    lg::set_run_id(0);
    lg::set_worker_id(0);
  }
};

// Sets an environment variable for the scope (child processes inherit it).
struct ScopedEnv {
  std::string name;
  ScopedEnv(const char* n, const char* v) : name(n) { setenv(n, v, 1); }
  ~ScopedEnv() { unsetenv(name.c_str()); }
};

}  // namespace

TEST(Logging, ParsesExactlyTheSevenLevelNames) {
  const char* names[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};
  for (int i = 0; i < 7; ++i) {
    ASSERT_TRUE(lg::parse_level(names[i])) << names[i];
    EXPECT_EQ(static_cast<int>(*lg::parse_level(names[i])), i);
    EXPECT_STREQ(lg::level_name(*lg::parse_level(names[i])), names[i]);
  }
  EXPECT_EQ(lg::parse_level("WARN"), lg::Level::warn);  // case does not matter
  EXPECT_EQ(lg::parse_level("Debug"), lg::Level::debug);
  for (const char* bad : {"", "warning", "err", "inf", "info ", "loud", "0", "tracee"})
    EXPECT_FALSE(lg::parse_level(bad)) << "'" << bad << "'";
}

TEST(Logging, FlagWinsOverEnvironmentWhichWinsOverDefault) {
  EXPECT_EQ(lg::resolve_level("", nullptr), lg::Level::info);
  EXPECT_EQ(lg::resolve_level("", ""), lg::Level::info);
  EXPECT_EQ(lg::resolve_level("", "debug"), lg::Level::debug);
  EXPECT_EQ(lg::resolve_level("warn", "debug"), lg::Level::warn);
  EXPECT_EQ(lg::resolve_level("off", "trace"), lg::Level::off);
  // A good flag wins even over a bad environment value; a bad flag is an error whatever the env says.
  EXPECT_EQ(lg::resolve_level("error", "nonsense"), lg::Level::error);
  try {
    lg::resolve_level("loud", "debug");
    FAIL() << "a bad flag must throw";
  } catch (const lg::BadLevel& e) {
    EXPECT_NE(std::string(e.what()).find("--log-level 'loud'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(lg::kLevelNames), std::string::npos) << e.what();
  }
  try {
    lg::resolve_level("", "verbose");
    FAIL() << "a bad environment value must throw";
  } catch (const lg::BadLevel& e) {
    EXPECT_NE(std::string(e.what()).find("DICESIM_LOG_LEVEL='verbose'"), std::string::npos) << e.what();
  }
}

TEST(Logging, JsonLinesCarryComponentRunAndWorker) {
  RestoreLogging restore;
  const std::string file = unique_temp("log.jsonl");
  std::remove(file.c_str());
  lg::LogOptions o = lg::default_log_options();
  o.use_env = false;
  o.level = "info";
  o.file = file;
  o.component = "worker";
  lg::init(o);
  lg::set_run_id(4611686018427387905);  // above 2^53: must survive as a string
  lg::set_worker_id(77);
  spdlog::info("first \"quoted\" line\twith a tab");
  spdlog::debug("below the level: not written");
  lg::set_component("aggregate");
  lg::set_worker_id(0);
  spdlog::warn("second line");
  lg::flush();

  const std::vector<nlohmann::json> lines = read_json_lines(file);
  ASSERT_EQ(lines.size(), 2u);
  for (const auto& j : lines)
    for (const char* key : {"ts", "level", "component", "run", "worker", "msg"}) EXPECT_TRUE(j.contains(key)) << key << j;
  EXPECT_EQ(lines[0]["level"], "info");
  EXPECT_EQ(lines[0]["component"], "worker");
  EXPECT_EQ(lines[0]["run"], "4611686018427387905");
  EXPECT_EQ(lines[0]["worker"], "77");
  EXPECT_EQ(lines[0]["msg"], "first \"quoted\" line\twith a tab");
  EXPECT_EQ(lines[1]["level"], "warn");
  EXPECT_EQ(lines[1]["component"], "aggregate");
  EXPECT_TRUE(lines[1]["worker"].is_null());
  const std::string ts = lines[0]["ts"];
  EXPECT_EQ(ts.size(), 24u) << ts;  // 2026-01-02T03:04:05.678Z
  EXPECT_EQ(ts.back(), 'Z');
  std::remove(file.c_str());
}

TEST(Logging, BadLevelIsBadInputNamingTheAllowedValues) {
  // Before and after the subcommand name, and from the environment.
  for (const char* args : {"--log-level loud info scenes/fair.toml", "info scenes/fair.toml --log-level loud"}) {
    const auto r = run_dicesim(args);
    dicesim::testing::expect_bad_input(r, {"loud", lg::kLevelNames});
  }
  ScopedEnv env("DICESIM_LOG_LEVEL", "verbose");
  dicesim::testing::expect_bad_input(run_dicesim("info scenes/fair.toml"), {"DICESIM_LOG_LEVEL", "verbose", lg::kLevelNames});
  // ... but a good flag overrides a bad environment.
  EXPECT_EQ(run_dicesim("info scenes/fair.toml --log-level warn").code, 0);
}

TEST(Logging, CommandLineFlagWinsOverEnvironment) {
  const auto plain = run_dicesim("info scenes/fair.toml");
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_EQ(plain.err.find("command line:"), std::string::npos) << "info level must not show debug lines";
  {
    ScopedEnv env("DICESIM_LOG_LEVEL", "debug");
    const auto from_env = run_dicesim("info scenes/fair.toml");
    EXPECT_NE(from_env.err.find("command line:"), std::string::npos) << from_env.err;
    EXPECT_NE(from_env.err.find("[info run=- worker=-]"), std::string::npos) << from_env.err;  // component = subcommand
    const auto flag = run_dicesim("info scenes/fair.toml --log-level warn");
    EXPECT_EQ(flag.err.find("command line:"), std::string::npos) << flag.err;
    EXPECT_EQ(flag.out, plain.out) << "logging must never touch stdout";
  }
  ScopedEnv env("DICESIM_LOG_LEVEL", "warn");
  const auto flag = run_dicesim("--log-level debug info scenes/fair.toml");
  EXPECT_NE(flag.err.find("command line:"), std::string::npos) << flag.err;
  EXPECT_EQ(flag.out, plain.out) << "logging must never touch stdout";
}

TEST(Logging, LogFileFromTheCommandLine) {
  const std::string file = unique_temp("cli.jsonl");
  std::remove(file.c_str());
  const auto r = run_dicesim("info scenes/fair.toml --log-level debug --log-file " + file);
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<nlohmann::json> lines = read_json_lines(file);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0]["component"], "info");
  EXPECT_EQ(lines[0]["level"], "debug");
  EXPECT_NE(lines[0]["msg"].get<std::string>().find("command line:"), std::string::npos);
  std::remove(file.c_str());
  // A file inside a file cannot be created (spdlog would create missing directories).
  dicesim::testing::expect_bad_input(run_dicesim("info scenes/fair.toml --log-file README.md/x.jsonl"),
                                     {"README.md/x.jsonl"});
}

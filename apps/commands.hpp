// The dicesim subcommands. Each registers itself on the CLI11 app and, when chosen, stores its
// exit code: 0 ok, 1 failed, 2 bad input.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "messages/run_spec.hpp"
#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

inline constexpr int kExitOk = 0, kExitFailed = 1, kExitBadInput = 2;

// SCENE plus --set and --fidelity, shared by every command that reads a scene.
struct SceneArgs {
  std::string path;
  std::vector<std::string> overrides;
  std::string fidelity;
  void add_to(CLI::App* cmd);
  SceneDef load() const;  // throws SceneError
  // The overrides load() applies, in order: every --set, then --fidelity as sim.fidelity="F" (provenance).
  std::vector<std::string> applied_overrides() const;
};

// --key-file FILE (authenticated runs, messages/auth.hpp), with the same help on every command.
CLI::Option* add_key_file_option(CLI::App* cmd, std::string& path);
// The key in FILE, or none for an empty path. Throws wire::KeyError (bad input, exit 2).
std::vector<std::uint8_t> load_run_key(const std::string& path);

void register_toss(CLI::App& app, int& exit_code);
void register_info(CLI::App& app, int& exit_code);
void register_bench(CLI::App& app, int& exit_code);
// `dicesim bench tradeoff SCENE ...` (cmd_tradeoff.cpp): argv[0] is "tradeoff".
int run_bench_tradeoff(int argc, char** argv);
void register_sweep(CLI::App& app, int& exit_code);      // cmd_sweep.cpp
void register_calibrate(CLI::App& app, int& exit_code);  // cmd_calibrate.cpp
void register_compare(CLI::App& app, int& exit_code);    // cmd_compare.cpp
void register_fit(CLI::App& app, int& exit_code);        // cmd_fit.cpp
void register_power(CLI::App& app, int& exit_code);      // cmd_power.cpp
void register_worker(CLI::App& app, int& exit_code);
void register_aggregate(CLI::App& app, int& exit_code);
void register_run(CLI::App& app, int& exit_code);
void register_bridge(CLI::App& app, int& exit_code);  // cmd_bridge.cpp
void register_watch(CLI::App& app, int& exit_code);   // cmd_watch.cpp
void register_record(CLI::App& app, int& exit_code);  // cmd_record.cpp
void register_replay(CLI::App& app, int& exit_code);  // cmd_replay.cpp
void register_merge(CLI::App& app, int& exit_code);   // cmd_merge.cpp: shards of `toss --shard`
void register_hub(CLI::App& app, int& exit_code);     // cmd_hub.cpp: LCM's TCP hub
void register_version(CLI::App& app, int& exit_code); // cmd_version.cpp

// Distributed runs (cmd_aggregate.cpp): what `aggregate` and `run` share.
struct AggregateArgs {
  SceneArgs scene;
  std::string lcm;
  std::uint64_t tosses = 100000;
  CLI::Option* tosses_opt = nullptr;  // given explicitly? (with a target it is only a cap)
  std::uint64_t seed = 1;
  int trace_every = 0;
  double target_halfwidth = 0.0;
  double timeout_s = 0.0;
  bool json = false;
  std::string key_file;    // --key-file: an authenticated run
  std::string checkpoint;  // --checkpoint FILE (aggregate only)
  std::string resume;      // --resume FILE (aggregate only): the run, from its checkpoint
  void add_to(CLI::App* cmd);
  void add_checkpoint_options(CLI::App* cmd);  // --checkpoint, --resume; SCENE becomes optional
};
// A new run (not --resume) compiled once: its model and what run_start announces. `run` makes it
// before forking its workers, which then start with both (no run_start wait, no compile of their own).
struct PreparedRun {
  DieModel model;
  wire::RunSpec spec;
};
// Throws SceneError (bad input, exit 2) and std::runtime_error (a scene that does not rebuild).
PreparedRun prepare_run(const AggregateArgs& a, std::int64_t run_id);
// Starts the run on `url`, aggregates it to the end and prints the report as `toss` does.
// `workers` (> 0) is reported as the thread count; `on_tick` may return an error to abort.
// `prepared`: the run, already compiled (prepare_run with this `a`); else it is compiled here.
// `on_session_end`: called as soon as the run is over, before the report (run stops its workers).
int aggregate_and_report(const AggregateArgs& a, const std::string& url, std::int64_t run_id, int workers,
                         const std::function<std::string()>& on_tick, const std::atomic<bool>* cancel,
                         const PreparedRun* prepared = nullptr, const std::function<void()>& on_session_end = {});
// The body of `dicesim worker --lcm URL --quiet --run ID --once [--key-file FILE]` in a child that
// `run` forked without exec (worker_processes.cpp): it serves `run` from the start. Returns the
// exit code.
int serve_forked_worker(const std::string& url, const std::string& key_file, const PreparedRun& run);

// --log-level and --log-file on `app` and each of its subcommands; logging is set up (logger/log.hpp)
// once parsing is complete, before the subcommand runs (log_options.cpp). parse_and_run calls it.
void add_log_options(CLI::App& app, int argc, char** argv);

// Parses argv into `app` and runs the chosen callback (which sets exit_code); maps errors to exit
// codes: help 0, bad usage or SceneError 2 (message on stderr, nothing on stdout), others 1.
int parse_and_run(CLI::App& app, int argc, char** argv, const int& exit_code);

// Runs the command line; returns the process exit code. main() only calls this.
int run_cli(int argc, char** argv);

}  // namespace dicesim

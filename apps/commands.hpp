// The dicesim subcommands. Each registers itself on the CLI11 app and, when chosen, stores its
// exit code: 0 ok, 1 failed, 2 bad input.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "sim/scene.hpp"

namespace dicesim {

inline constexpr int kExitOk = 0, kExitFailed = 1, kExitBadInput = 2;

// SCENE plus --set and --fidelity, shared by every command that reads a scene.
struct SceneArgs {
  std::string path;
  std::vector<std::string> overrides;
  std::string fidelity;
  void add_to(CLI::App* cmd);
  SceneDef load() const;  // throws SceneError
};

void register_toss(CLI::App& app, int& exit_code);
void register_info(CLI::App& app, int& exit_code);
void register_bench(CLI::App& app, int& exit_code);

// Runs the command line; returns the process exit code. main() only calls this.
int run_cli(int argc, char** argv);

}  // namespace dicesim

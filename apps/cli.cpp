#include <cstdio>
#include <algorithm>
#include <cstdint>
#include <exception>
#include <string_view>
#include <vector>

#include "aggregator/checkpoint.hpp"
#include "apps/commands.hpp"
#include "apps/provenance.hpp"
#include "apps/shard_file.hpp"
#include "apps/fidelity_name.hpp"
#include "apps/number_forms.hpp"
#include "messages/auth.hpp"
#include "sim/scene/fidelity.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim {

void SceneArgs::add_to(CLI::App* cmd) {
  cmd->add_option("SCENE", path, "Scene file (TOML), e.g. scenes/paper/die1.toml")->required();
  cmd->add_option("--set", overrides,
                  "Override a scene key, KEY=VALUE in TOML syntax; repeatable.\n"
                  "e.g. --set materials.steel.restitution=1.0 --set throw.spin.sd=30\n"
                  "Array elements by index: --set 'die.regions[0].cuts[0].offset=0.005'")
      ->type_name("KEY=VALUE");
  cmd->add_option("--fidelity", fidelity, "Physical model (the scene's sim.fidelity otherwise): static, paper, impulse, stepped, auto")
      ->type_name("F");
}

void check_fidelity_name(const std::string& fidelity) {
  if (!fidelity.empty() && !parse_fidelity(fidelity))
    throw SceneError("--fidelity", "", "", "'" + fidelity + "' is not a fidelity; " + kFidelityChoices);
}

std::vector<std::string> SceneArgs::applied_overrides() const {
  std::vector<std::string> all = overrides;
  check_fidelity_name(fidelity);
  if (!fidelity.empty()) all.push_back("sim.fidelity=\"" + fidelity + "\"");
  return all;
}

SceneDef SceneArgs::load() const { return load_scene(path, applied_overrides()); }

CLI::Option* add_key_file_option(CLI::App* cmd, std::string& path) {
  return cmd->add_option("--key-file", path,
                         "Authenticated run: seal every message sent with HMAC-SHA-256 under the key in FILE, and\n"
                         "drop (and count) every message received without a valid seal. Every process of the run\n"
                         "needs the same file: hex digits, at least 64 (32 bytes), mode 0600 or 0400, owned by\n"
                         "you or root. Make one: (umask 077; openssl rand -hex 32 > run.key). README, Security")
      ->type_name("FILE");
}

std::vector<std::uint8_t> load_run_key(const std::string& path) {
  return path.empty() ? std::vector<std::uint8_t>{} : wire::load_key_file(path);
}

int parse_and_run(CLI::App& app, int argc, char** argv, const int& exit_code) {
  add_log_options(app, argc, argv);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s\nRun with --help for usage.\n", app.get_name().c_str(), e.what());
    return kExitBadInput;
  } catch (const SceneError& e) {
    std::fprintf(stderr, "dicesim: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const wire::KeyError& e) {
    std::fprintf(stderr, "dicesim: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const agg::CheckpointError& e) {
    std::fprintf(stderr, "dicesim: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const ShardError& e) {  // shard and fit part files (fit --points/--merge)
    std::fprintf(stderr, "dicesim: error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dicesim: failed: %s\n", e.what());
    return kExitFailed;
  }
  return exit_code;
}

// The browser commands (web/): declared here, not in commands.hpp, which every command includes.
void register_show(CLI::App& app, int& exit_code);   // cmd_show.cpp
void register_serve(CLI::App& app, int& exit_code);  // cmd_serve.cpp

namespace {

// Edits (insert, delete, replace, swap of neighbours) from a to b: how far a typo is from a command.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// `dicesim tos ...`: CLI11 would only say a subcommand is required. Name the word and the closest
// command (a prefix counts as close: `dicesim sw` -> sweep).
int unknown_command(const CLI::App& app, std::string_view word) {
  std::string best;
  std::size_t best_d = SIZE_MAX;
  for (const CLI::App* sub : app.get_subcommands({})) {
    const std::string& name = sub->get_name();
    const std::size_t d = name.rfind(word, 0) == 0 ? 1 : edit_distance(word, name);
    if (d < best_d) best_d = d, best = name;
  }
  std::string names;
  for (const CLI::App* sub : app.get_subcommands({})) names += (names.empty() ? "" : ", ") + sub->get_name();
  if (best_d <= std::max<std::size_t>(2, word.size() / 3))
    std::fprintf(stderr, "dicesim: unknown command '%.*s'; did you mean '%s'?\nCommands: %s (dicesim --help)\n",
                 static_cast<int>(word.size()), word.data(), best.c_str(), names.c_str());
  else
    std::fprintf(stderr, "dicesim: unknown command '%.*s'\nCommands: %s (dicesim --help)\n",
                 static_cast<int>(word.size()), word.data(), names.c_str());
  return kExitBadInput;
}

}  // namespace

int run_cli(int argc, char** argv) {
  // `dicesim bench tradeoff SCENE` lives next to `dicesim bench SCENE` (whose SCENE is positional).
  if (argc >= 3 && std::string_view(argv[1]) == "bench" && std::string_view(argv[2]) == "tradeoff")
    return run_bench_tradeoff(argc - 2, argv + 2);
  CLI::App app{
      "dicesim: how likely is each face of a real, possibly unfair die?\n"
      "Simulates physical tosses (flight, bounces, rest) of a die of any density layout.\n\n"
      "Start with:  dicesim toss scenes/paper/die1.toml\n"
      "             dicesim info scenes/paper/die1.toml\n"
      "Exit codes: 0 ok, 1 failed, 2 bad input (file, key, value or range named on stderr).",
      "dicesim"};
  app.require_subcommand(1);
  app.fallthrough(false);
  int exit_code = kExitOk;
  register_toss(app, exit_code);
  register_info(app, exit_code);
  register_bench(app, exit_code);
  app.get_subcommand("bench")->footer(
      "\nSpeed against accuracy of the fidelity ladder:  dicesim bench tradeoff SCENE --help");
  register_sweep(app, exit_code);
  register_calibrate(app, exit_code);
  register_compare(app, exit_code);
  register_fit(app, exit_code);
  register_power(app, exit_code);
  register_worker(app, exit_code);
  register_aggregate(app, exit_code);
  register_run(app, exit_code);
  register_bridge(app, exit_code);
  register_watch(app, exit_code);
  register_record(app, exit_code);
  register_replay(app, exit_code);
  register_show(app, exit_code);
  register_serve(app, exit_code);
  register_merge(app, exit_code);
  register_hub(app, exit_code);
  register_version(app, exit_code);
  app.set_version_flag("--version", std::string("dicesim ") + git_describe(), "Print the version and exit (dicesim version: the build)");
  accept_number_forms(app);
  if (argc >= 2 && argv[1][0] != '-') {
    const auto subs = app.get_subcommands({});
    if (std::none_of(subs.begin(), subs.end(), [&](const CLI::App* s) { return s->check_name(argv[1]); }))
      return unknown_command(app, argv[1]);
  }
  return parse_and_run(app, argc, argv, exit_code);
}

}  // namespace dicesim

// dicesim version: how this binary was built (dicesim --version prints the version alone).
#include <cstdio>

#include <nlohmann/json.hpp>

#include "apps/build_config.hpp"
#include "apps/commands.hpp"
#include "apps/provenance.hpp"

namespace dicesim {
namespace {

int run_version(bool json) {
  const BuildConfig c = build_config();
  const Provenance p;  // its version and dirty flag
  if (json) {
    nlohmann::json libs = nlohmann::json::object();
    for (const auto& [name, v] : c.libraries) libs[name] = v.empty() ? nlohmann::json(nullptr) : nlohmann::json(v);
    const nlohmann::json j = {{"version", p.version},
                              {"dirty", p.dirty < 0 ? nlohmann::json(nullptr) : nlohmann::json(p.dirty == 1)},
                              {"compiler", c.compiler},
                              {"build_type", c.build_type},
                              {"cxx_flags", c.cxx_flags},
                              {"libraries", libs}};
    std::printf("%s\n", j.dump().c_str());
    return kExitOk;
  }
  std::printf("dicesim %s%s\ncompiler    %s (%s)\nflags       %s\nlibraries\n", p.version.c_str(),
              p.dirty < 0 ? " (not built from a git checkout)" : "", c.compiler.c_str(), c.build_type.c_str(),
              c.cxx_flags.c_str());
  for (const auto& [name, v] : c.libraries) std::printf("  %-14s %s\n", name.c_str(), v.empty() ? "(not known)" : v.c_str());
  return kExitOk;
}

}  // namespace

void register_version(CLI::App& app, int& exit_code) {
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("version",
                                     "Print the version (git describe at build time; \"-dirty\": built with uncommitted\n"
                                     "changes), the compiler, its flags and the library versions found at configure time.\n\n"
                                     "Examples:\n"
                                     "  dicesim version\n"
                                     "  dicesim version --json\n"
                                     "  dicesim --version            # the version alone");
  cmd->add_flag("--json", *json, "Print exactly one JSON object on stdout instead of the text");
  cmd->callback([json, &exit_code] { exit_code = run_version(*json); });
}

}  // namespace dicesim

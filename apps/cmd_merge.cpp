// dicesim merge: the shards of one run (`toss --shard I/N --out FILE`) added into that run's report.
#include <cstdio>
#include <memory>

#include "apps/commands.hpp"
#include "apps/report.hpp"
#include "apps/shard_file.hpp"

namespace dicesim {
namespace {

struct MergeArgs {
  std::vector<std::string> files;
  bool json = false;
};

int run_merge(const MergeArgs& a) {
  try {
    std::vector<ShardPart> parts;
    for (const std::string& f : a.files) parts.push_back(read_shard_file(f));
    print_report(merge_shards(parts), a.json);
    return kExitOk;
  } catch (const ShardError& e) {
    std::fprintf(stderr, "dicesim: error: %s\n", e.what());
    return kExitBadInput;
  }
}

}  // namespace

void register_merge(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<MergeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "merge",
      "Add the shard files of one run (dicesim toss --shard I/N --out FILE) and print the report of the\n"
      "whole run, as one `dicesim toss` of all its tosses prints it: identical counts, p, intervals and\n"
      "tests. tosses is the whole run; threads and elapsed_s are the shards' added (compute, not wall time).\n"
      "Refuses (exit 2, naming the file) shards of different builds, scenes, models, seeds, fidelities or\n"
      "run sizes, a shard given twice and a shard missing.\n\n"
      "Examples:\n"
      "  for i in 0 1 2 3; do dicesim toss scenes/paper/die1.toml -n 1000000 --shard $i/4 --out part-$i.json; done\n"
      "  dicesim merge part-*.json\n"
      "  dicesim merge --json part-*.json > run.json");
  cmd->add_option("FILES", args->files, "Shard files, one per shard I = 0..N-1, in any order")->required();
  cmd->add_flag("--json", args->json, "Print exactly one JSON object on stdout instead of the table");
  cmd->callback([args, &exit_code] { exit_code = run_merge(*args); });
}

}  // namespace dicesim

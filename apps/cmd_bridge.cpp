// dicesim bridge: republish a dicesim LCM bus on DDS (bridge/README.md) until SIGINT/SIGTERM.
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include <spdlog/spdlog.h>

#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "bridge/bridge.hpp"
#include "bridge/dds_config.hpp"
#include "logger/log.hpp"
#include "messages/wire.hpp"

namespace dicesim {
namespace {

struct BridgeArgs {
  std::string lcm;
  std::string dds_config;
  std::uint32_t domain = 0;
  std::string key_file;
};

int run_bridge_command(const BridgeArgs& a) {
  logging::set_component("bridge");  // it serves every run on the bus: no run id of its own
  bridge::BridgeDef def = bridge::default_bridge_def();
  def.lcm_url = wire::resolve_url(a.lcm);
  def.dds_domain = a.domain;
  def.stop = &g_stop;
  def.key = load_run_key(a.key_file);  // KeyError: bad input, exit 2 (parse_and_run)
  try {
    const bridge::DdsConfigChoice cfg =
        bridge::resolve_dds_config(a.dds_config, std::getenv("CYCLONEDDS_URI"), bridge::executable_dir());
    def.dds_config = cfg.uri;
    spdlog::info("bridge: DDS configuration {} ({})", cfg.uri.size() > 200 ? cfg.uri.substr(0, 200) + "..." : cfg.uri,
                 cfg.source);
    std::signal(SIGINT, on_stop_signal);
    std::signal(SIGTERM, on_stop_signal);
    const bridge::BridgeStats s = bridge::run_bridge(def);
    std::fprintf(stderr,
                 "dicesim: bridge stopped: %lld answers and %lld run statuses published from %lld runs; "
                 "%lld malformed and %lld unauthenticated LCM messages ignored, %lld DDS write errors\n",
                 static_cast<long long>(s.answers), static_cast<long long>(s.statuses), static_cast<long long>(s.runs),
                 static_cast<long long>(s.malformed), static_cast<long long>(s.unauthenticated),
                 static_cast<long long>(s.write_errors));
    return s.write_errors == 0 ? kExitOk : kExitFailed;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dicesim: bridge failed: %s\n", e.what());
    return kExitFailed;
  }
}

}  // namespace

void register_bridge(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<BridgeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "bridge",
      "Republish dicesim runs on DDS (Cyclone DDS) for any DDS program to subscribe to: every\n"
      "DICESIM_PROBABILITIES answer goes out at once on topic dicesim_probabilities (keyed by run id;\n"
      "reliable, transient-local, keep-last 1: a late subscriber gets each run's latest answer), and\n"
      "what is known of each run (announced / running / finished / silent, workers) on\n"
      "dicesim_run_status. Runs until Ctrl-C or SIGTERM; aggregators and runs may come and go.\n"
      "DDS configuration: --dds-config FILE, else $CYCLONEDDS_URI, else bridge/cyclonedds-loopback.xml\n"
      "(loopback only: nothing leaves this host).\n\n"
      "Examples:\n"
      "  dicesim bridge &\n"
      "  dicesim bridge --lcm 'udpm://239.255.76.67:7667?ttl=1' --dds-config my-lan.xml\n"
      "  CYCLONEDDS_URI=file://$PWD/bridge/cyclonedds-loopback.xml build/bridge/examples/dicesim_dds_subscriber");
  cmd->add_option("--lcm", args->lcm,
                  "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0, which never leaves this host)")
      ->type_name("URL");
  cmd->add_option("--dds-config", args->dds_config, "Cyclone DDS configuration file (default: see above)")
      ->type_name("FILE")
      ->check(CLI::ExistingFile);  // a missing file is bad input (exit 2), caught before anything opens
  add_key_file_option(cmd, args->key_file)
      ->description("Bridge only an authenticated run's messages: those whose HMAC-SHA-256 seal opens with the key\n"
                    "in FILE (others are dropped and counted). DDS itself is not authenticated by this: secure the\n"
                    "DDS side with DDS Security or a trusted network. README, Security");
  cmd->add_option("--dds-domain", args->domain, "DDS domain id")->capture_default_str()->check(CLI::Range(0, 230));
  cmd->callback([args, &exit_code] { exit_code = run_bridge_command(*args); });
}

}  // namespace dicesim

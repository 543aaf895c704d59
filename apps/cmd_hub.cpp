// dicesim hub: LCM's own TCP hub (lcm.lcm.TCPService, liblcm-java) in the foreground, for runs
// whose processes cannot reach each other by multicast (apps/lcm_hub.hpp).
#include <unistd.h>

#include <cstdio>
#include <memory>

#include "apps/commands.hpp"
#include "apps/lcm_hub.hpp"

namespace dicesim {
namespace {

struct HubArgs {
  int port = 7700;
  bool print_command = false;
};

int run_hub(const HubArgs& a) {
  const std::vector<std::string> cmd = hub_command(a.port);
  if (a.print_command) {
    for (std::size_t i = 0; i < cmd.size(); ++i) std::printf("%s%s", i ? " " : "", cmd[i].c_str());
    std::printf("\n");
    return kExitOk;
  }
  if (const std::string why = hub_missing(); !why.empty()) {
    std::fprintf(stderr, "dicesim: failed: %s\n", why.c_str());
    return kExitFailed;
  }
  std::fprintf(stderr, "dicesim: LCM TCP hub on port %d (every interface); clients: --lcm tcpq://THIS_HOST:%d\n", a.port, a.port);
  std::fflush(stderr);
  std::vector<char*> argv;
  for (const std::string& s : cmd) argv.push_back(const_cast<char*>(s.c_str()));
  argv.push_back(nullptr);
  ::execvp(argv[0], argv.data());
  std::perror("dicesim: failed: exec java");
  return kExitFailed;
}

}  // namespace

void register_hub(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<HubArgs>();
  CLI::App* cmd = app.add_subcommand(
      "hub",
      "Run LCM's own TCP hub (lcm.lcm.TCPService from Debian's liblcm-java, on a Java runtime) in the\n"
      "foreground, for networks without multicast (Kubernetes, clouds, many clusters): every process of\n"
      "a run connects to it with --lcm tcpq://HOST:PORT and it relays every message to every subscriber.\n"
      "It listens on every interface, unauthenticated: use --key-file for runs over networks you do\n"
      "not trust (docs/scaling-out.md). Stop it with Ctrl-C.\n\n"
      "Examples:\n"
      "  dicesim hub --port 7700 &\n"
      "  dicesim worker --lcm tcpq://HUBHOST:7700 &   # on each worker host\n"
      "  dicesim aggregate scenes/paper/die1.toml -n 1000000 --lcm tcpq://HUBHOST:7700");
  cmd->add_option("-p,--port", args->port, "TCP port to listen on")->capture_default_str()->check(CLI::Range(1, 65535));
  cmd->add_flag("--print-command", args->print_command, "Print the java command line instead of running it");
  cmd->callback([args, &exit_code] { exit_code = run_hub(*args); });
}

}  // namespace dicesim

// dicesim serve: a local web page following the live run on the LCM bus (web/).
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "messages/lcm_wait.hpp"
#include "apps/commands.hpp"
#include "messages/wire.hpp"
#include "sim/scene/scene_error.hpp"
#include "web/live_board.hpp"
#include "web/page_server.hpp"

namespace dicesim {
namespace {

std::atomic<bool> g_stop{false};
void on_stop_signal(int) { g_stop = true; }

struct ServeArgs {
  std::string lcm;
  std::string bind = "127.0.0.1";
  int port = 8037;
  std::string key_file;
  double timeout_s = 0.0;
};

// Feeds the board from the bus.
struct Listener {
  web::LiveBoard* board;
  void handle(const lcm::ReceiveBuffer* rb, const std::string& channel) { board->handle(channel, rb->data, rb->data_size); }
};

int serve(const ServeArgs& a) {
  web::LiveBoard board(load_run_key(a.key_file));
  web::PageServer server(board);
  if (!server.bind(a.bind, a.port))
    throw SceneError("dicesim serve", "--port", a.bind + ":" + std::to_string(a.port),
                     "cannot be bound (in use, or not an address of this host): choose another --port or --bind");
  const std::string url = wire::resolve_url(a.lcm);
  lcm::LCM bus(url);
  if (!bus.good()) {
    std::fprintf(stderr, "dicesim: failed: cannot open LCM at '%s'\n", url.c_str());
    return kExitFailed;
  }
  Listener listener{&board};
  bus.subscribe(wire::kProbabilities, &Listener::handle, &listener);
  bus.subscribe(wire::kWorkerStatus, &Listener::handle, &listener);
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  std::thread http([&server] { server.run(); });
  std::fprintf(stderr, "dicesim serve: http://%s:%d/ following runs on %s (Ctrl-C stops)\n", a.bind.c_str(), server.port(),
               url.c_str());
  const auto t0 = std::chrono::steady_clock::now();
  while (!g_stop) {
    wire::listen_timeout(bus, 100);
    if (a.timeout_s > 0 && std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > a.timeout_s) break;
  }
  server.stop();
  http.join();
  return kExitOk;
}

}  // namespace

void register_serve(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ServeArgs>();
  CLI::App* cmd = app.add_subcommand(
      "serve",
      "A local web page following the live run on the LCM bus: each outcome's probability with its\n"
      "95% interval as bars updated in place (server-sent events fed from the aggregator's\n"
      "DICESIM_PROBABILITIES, at most 4 a second), progress, rate and ETA, the workers and their\n"
      "health (heartbeats on DICESIM_WORKER_STATUS), rejected and unauthenticated message counts.\n"
      "A finished run stays on the page until the next run answers. Also GET /state (JSON) and\n"
      "/events (the event stream).\n\n"
      "It binds 127.0.0.1: only this machine can open the page. --bind 0.0.0.0 (or one address)\n"
      "lets anyone who can reach that address read the run's state (outcomes, counts, worker\n"
      "hosts and pids), without a password; it cannot change anything (the server only reads).\n\n"
      "Examples:  dicesim serve            (then open http://127.0.0.1:8037/)\n"
      "           dicesim serve --port 9000 --lcm 'udpm://239.255.76.67:7667?ttl=1'");
  cmd->add_option("--lcm", args->lcm,
                  "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0, which never leaves this host)")
      ->type_name("URL");
  cmd->add_option("--port", args->port, "TCP port of the page (0: any free port, printed)")->capture_default_str()->check(
      CLI::Range(0, 65535));
  cmd->add_option("--bind", args->bind, "Address to listen on (127.0.0.1: this machine only; see above)")
      ->capture_default_str()
      ->type_name("ADDR");
  add_key_file_option(cmd, args->key_file)->description("An authenticated run: show only messages whose HMAC-SHA-256 seal opens with the key in FILE");
  cmd->add_option("--timeout", args->timeout_s, "Stop after this many seconds (0: never)")->type_name("S")->check(CLI::Range(0.0, 1e9));
  cmd->callback([args, &exit_code] { exit_code = serve(*args); });
}

}  // namespace dicesim

// dicesim serve: a local web page following the live run on the LCM bus (web/).
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "messages/lcm_wait.hpp"
#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "apps/info_json.hpp"
#include "messages/run_spec.hpp"
#include "messages/wire.hpp"
#include "sim/body/material_parts.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene_error.hpp"
#include "sim/scene/scene_hash.hpp"
#include "web/live_board.hpp"
#include "web/page_server.hpp"
#include "web/show_data.hpp"
#include "web/show_page.hpp"

namespace dicesim {
namespace {

struct ServeArgs {
  std::string lcm;
  std::string bind = "127.0.0.1";
  int port = 8037;
  std::string key_file;
  double timeout_s = 0.0;
  std::uint64_t trace_every = 0;
};

// Feeds the board from the bus.
struct Listener {
  web::LiveBoard* board;
  void handle(const lcm::ReceiveBuffer* rb, const std::string& channel) { board->handle(channel, rb->data, rb->data_size); }
};

// --trace-every: the `dicesim show` page of toss I of the run, made here with the run's model, seed
// and fidelity as its run_start describes them (the same load and compile as a worker's, checked by
// the model's fingerprint), else as its answers' provenance names them if that scene file is
// readable here. The die's part of the page is made once per run.
class TracePages {
 public:
  explicit TracePages(const web::LiveBoard& board) : board_(board) {}

  web::PageServer::TracePage operator()(std::int64_t run_id, std::uint64_t index) {
    if (run_id != run_id_) prepare(run_id);
    if (!error_.empty()) return {404, error_page(error_)};
    if (total_ > 0 && index >= total_)
      return {404, error_page("toss " + std::to_string(index) + " is outside the run's indices 0.." + std::to_string(total_ - 1))};
    nlohmann::json page = page_;
    page["toss"] = web::toss_json(*model_, seed_, index);
    return {200, web::show_html(page)};
  }

 private:
  static std::string error_page(const std::string& why) {
    std::string text;
    for (const char c : why) text += c == '<' ? std::string("&lt;") : c == '&' ? std::string("&amp;") : std::string(1, c);
    return "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>no sampled toss</title></head><body "
           "style=\"font:14px system-ui,sans-serif;color:#8a1c10\"><p id=\"trace-error\">No sampled toss: " + text + "</p></body></html>";
  }
  void build(const SceneDef& def, const std::string& path, const std::string& origin) {
    model_ = compile(def, origin);
    page_ = {{"scene", origin}, {"die", web::die_json(*model_, def)}, {"info", info_json(origin, *model_, material_parts(def, path))}};
  }
  void prepare(std::int64_t run_id) {
    run_id_ = run_id;
    error_.clear();
    model_.reset();
    try {
      if (const auto spec = board_.run_spec(run_id)) {
        wire::with_spec_files(*spec, [&](const std::string& path, const std::vector<std::string>& o) {
          build(load_scene(path, o), path, spec->origin);
        });
        if (wire::model_fingerprint(*model_) != spec->fingerprint)
          error_ = "this dicesim build compiles the run's scene '" + spec->origin +
                   "' into another model (its fingerprint differs): its tosses would not be the run's";
        seed_ = spec->seed;
        total_ = spec->total;
        return;
      }
      // No run_start heard (a sealed one without the key, a recording without it): the provenance.
      const nlohmann::json p = board_.provenance(run_id);
      if (!p.is_object() || !p.contains("scene")) {
        error_ = "the run's scene is unknown here: no run_start heard, and its answers name no scene";
        return;
      }
      const std::string scene = p["scene"].get<std::string>();
      const auto overrides = p.value("overrides", std::vector<std::string>{});
      if (!std::filesystem::is_regular_file(scene)) {
        error_ = "the run's scene file '" + scene + "' is not reachable from here (no run_start heard, and " +
                 std::filesystem::absolute(scene).string() + " cannot be read)";
        return;
      }
      if (scene_sha256(scene, overrides) != p.value("scene_sha256", "")) {
        error_ = "the scene file '" + scene + "' here is not the run's (its resolved sha256 differs from the run's provenance)";
        return;
      }
      build(load_scene(scene, overrides), scene, scene);
      seed_ = p.value("seed", std::uint64_t{0});
      total_ = p.value("tosses", std::uint64_t{0});
    } catch (const std::exception& e) {
      model_.reset();
      error_ = std::string("the run's scene cannot be rebuilt here: ") + e.what();
    }
  }

  const web::LiveBoard& board_;
  std::int64_t run_id_ = 0;
  std::optional<DieModel> model_;
  nlohmann::json page_;
  std::uint64_t seed_ = 0, total_ = 0;
  std::string error_;
};

int serve(const ServeArgs& a) {
  web::LiveBoard board(load_run_key(a.key_file), a.trace_every);
  web::PageServer server(board);
  if (a.trace_every > 0) server.set_trace_pages([pages = std::make_shared<TracePages>(board)](std::int64_t run, std::uint64_t index) {
    return (*pages)(run, index);
  });
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
  if (a.trace_every > 0) bus.subscribe(wire::kRunStart, &Listener::handle, &listener);
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
      "--trace-every K: the page also animates sampled tosses of the run, in `dicesim show`'s 3-D\n"
      "viewer: toss K*floor((done-1)/K), the latest K-th index the run has reached, made here by\n"
      "this process from the run's scene, seed and fidelity as its run_start describes them (the\n"
      "page of `dicesim show SCENE --seed S --toss I`; also GET /trace?run=RUN&index=I). If the\n"
      "scene cannot be rebuilt here, the page says why.\n\n"
      "It binds 127.0.0.1: only this machine can open the page. --bind 0.0.0.0 (or one address)\n"
      "lets anyone who can reach that address read the run's state (outcomes, counts, worker\n"
      "hosts and pids; with --trace-every also the die's geometry and sampled tosses), without a\n"
      "password; it cannot change anything (the server only reads).\n\n"
      "Examples:  dicesim serve            (then open http://127.0.0.1:8037/)\n"
      "           dicesim serve --port 9000 --lcm 'udpm://239.255.76.67:7667?ttl=1'\n"
      "           dicesim serve --trace-every 10000   (every 10000th toss animated)");
  cmd->add_option("--lcm", args->lcm,
                  "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0, which never leaves this host)")
      ->type_name("URL");
  cmd->add_option("--port", args->port, "TCP port of the page (0: any free port, printed)")->capture_default_str()->check(
      CLI::Range(0, 65535));
  cmd->add_option("--bind", args->bind, "Address to listen on (127.0.0.1: this machine only; see above)")
      ->capture_default_str()
      ->type_name("ADDR");
  add_key_file_option(cmd, args->key_file)->description("An authenticated run: show only messages whose HMAC-SHA-256 seal opens with the key in FILE");
  cmd->add_option("--trace-every", args->trace_every, "Animate toss indices divisible by K, the latest the run has reached (see above)")
      ->type_name("K")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 62));
  cmd->add_option("--timeout", args->timeout_s, "Stop after this many seconds (0: never)")->type_name("S")->check(CLI::Range(0.0, 1e9));
  cmd->callback([args, &exit_code] { exit_code = serve(*args); });
}

}  // namespace dicesim

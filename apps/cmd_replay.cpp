// dicesim replay: a run recomputed from its LCM event log alone (logger/replay.hpp), optionally
// re-published at the recorded pace; or one traced toss checked against a re-simulation.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "aggregator/session.hpp"
#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "apps/report.hpp"
#include "messages/spec_scene.hpp"
#include "logger/event_log.hpp"
#include "logger/log.hpp"
#include "logger/replay.hpp"

namespace dicesim {
namespace {

struct ReplayArgs {
  std::string path;
  std::int64_t run = 0;
  bool json = false;
  bool live = false;
  std::string lcm;
  double speed = 1.0;
  std::int64_t toss = -1;  // --toss I
  std::string key_file;
};

int replay_run(const ReplayArgs& a) {
  eventlog::ReplayOptions opt = eventlog::default_replay_options();
  opt.path = a.path;
  opt.run_id = a.run;
  opt.live = a.live;
  opt.speed = a.speed;
  opt.cancel = &g_stop;
  opt.key = load_run_key(a.key_file);
  if (a.live) opt.url = wire::resolve_url(a.lcm);
  const auto t0 = std::chrono::steady_clock::now();
  const eventlog::ReplayResult res = eventlog::replay(opt);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  logging::set_run_id(res.spec.run_id);
  if (res.cancelled) {
    std::fprintf(stderr, "dicesim: interrupted\n");
    return kExitFailed;
  }
  spdlog::info("read {} events ({:.1f} MB) in {:.3f} s{}; the run took {:.1f} s when recorded", res.events,
               static_cast<double>(res.bytes) / 1e6, elapsed, a.live ? " (re-published at the recorded pace)" : "",
               res.run_span_s);
  spdlog::info("run {}: {}", res.spec.run_id, agg::health_line(res.health));
  // Each toss index once is the ideal; more were computed again after lost batches, expired
  // leases or an aggregator restart (or repeated on the wire).
  spdlog::info("toss results in the log: {} for {} tosses ({} more than once)", res.results_in_log, res.tosses,
               res.results_in_log > res.tosses ? res.results_in_log - res.tosses : 0);
  if (!res.other_runs.empty())
    spdlog::info("the log also holds {} other run(s), e.g. {} (choose with --run ID)", res.other_runs.size(),
                 res.other_runs.front());
  if (!res.model_matches)
    spdlog::warn("this build compiles the run's scene to a different model (fingerprint): the counts come from the "
                 "log, but --toss re-simulations will not agree");
  if (res.recorded_final) {
    if (!eventlog::same_as_recorded(res)) {
      std::fprintf(stderr, "dicesim: failed: the recomputed counts differ from the live run's final result in the log\n");
      return kExitFailed;
    }
    spdlog::info("identical to the live aggregator's final result recorded in the log");
  } else {
    spdlog::info("the log holds no final result of the live aggregator to compare with");
  }

  RunReport r;
  r.scene = res.spec.origin;
  r.fidelity = res.spec.fidelity;
  r.seed = res.spec.seed;
  r.threads = std::max(1, res.workers);
  r.tosses = res.tosses;
  r.counts = res.counts;
  // The live report's labels and fair-die expectation, from the same model when it is the run's.
  if (res.model_matches && res.model.outcome_labels == res.labels)
    set_labels(r, res.model);
  else
    r.labels.assign(res.labels.begin(), res.labels.end());
  r.elapsed_s = elapsed;
  // This build's version; the scene as the log's run_start describes it.
  std::string sha;
  try {
    sha = wire::spec_scene_sha256(res.spec);
  } catch (const std::exception&) {  // a scene this build no longer reads: its hash stays unknown
  }
  r.provenance = make_provenance(res.spec.origin, res.spec.overrides, sha, res.model, res.spec.seed, res.spec.total, r.threads);
  r.provenance.fidelity = res.spec.fidelity;
  print_report(r, a.json);
  return kExitOk;
}

int replay_toss(const ReplayArgs& a) {
  const eventlog::TossCheck c =
      eventlog::check_toss(a.path, a.run, static_cast<std::uint64_t>(a.toss), load_run_key(a.key_file));
  logging::set_run_id(c.spec.run_id);
  const char* verdict = c.bit_identical ? "agree (bit-identical)" : c.agree ? "agree" : "DISAGREE";
  const int sim_face = c.sim.status == TossStatus::Settled ? c.sim.face : 0;
  if (a.json) {
    nlohmann::json bounces = nlohmann::json::array();
    for (const dicesim_lcm::bounce_state& m : c.logged) {
      nlohmann::json b = {{"bounce", m.bounce},
                          {"t", m.t},
                          {"position", {m.position[0], m.position[1], m.position[2]}},
                          {"quaternion", {m.quaternion[0], m.quaternion[1], m.quaternion[2], m.quaternion[3]}},
                          {"velocity", {m.velocity[0], m.velocity[1], m.velocity[2]}},
                          {"angular_velocity", {m.angular_velocity[0], m.angular_velocity[1], m.angular_velocity[2]}},
                          {"velocity_after", {m.velocity_after[0], m.velocity_after[1], m.velocity_after[2]}},
                          {"angular_velocity_after",
                           {m.angular_velocity_after[0], m.angular_velocity_after[1], m.angular_velocity_after[2]}},
                          {"contact_vertex", m.contact_vertex},
                          {"impulse", m.impulse}};
      bounces.push_back(b);
    }
    nlohmann::json j = {{"run", std::to_string(c.spec.run_id)},
                        {"scene", c.spec.origin},
                        {"seed", c.spec.seed},
                        {"toss", c.index},
                        {"bounces_logged", c.logged.size()},
                        {"bounces_simulated", c.simulated.size()},
                        {"face_simulated", sim_face},
                        {"status_simulated", to_string(c.sim.status)},
                        {"max_abs_diff", c.max_abs_diff},
                        {"bit_identical", c.bit_identical},
                        {"agree", c.agree},
                        {"bounces", bounces}};
    if (c.batch_found) j["face_logged"] = c.log_face;
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("run %lld: %s (%s, seed %llu), toss %llu\n\n", static_cast<long long>(c.spec.run_id), c.spec.origin.c_str(),
                c.spec.fidelity.c_str(), static_cast<unsigned long long>(c.spec.seed),
                static_cast<unsigned long long>(c.index));
    std::printf("bounce     t [s]      z [m]   |v| in [m/s]  |v| out [m/s]  vertex  impulse [N s]\n");
    for (const dicesim_lcm::bounce_state& m : c.logged) {
      auto norm = [](const double (&v)[3]) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
      std::printf("%6d  %9.6f  %9.6f  %13.6f  %13.6f  %6d  %13.6g\n", m.bounce, m.t, m.position[2], norm(m.velocity),
                  norm(m.velocity_after), m.contact_vertex, m.impulse);
    }
    std::printf("\nlogged: %zu bounce state(s)%s", c.logged.size(),
                c.batch_found ? (", result face " + std::to_string(c.log_face) + ", " + std::to_string(c.log_bounces) +
                                 " impacts").c_str()
                              : " (its toss_batch is not in the log)");
    std::printf("\nre-simulated from (scene, seed %llu, toss %llu): face %d (%s), %d impacts\n",
                static_cast<unsigned long long>(c.spec.seed), static_cast<unsigned long long>(c.index), sim_face,
                to_string(c.sim.status), c.sim.bounces);
    std::printf("largest difference %.3g: %s\n", c.max_abs_diff, verdict);
  }
  if (!c.model_matches) spdlog::warn("this build compiles the run's scene to a different model (fingerprint)");
  if (!c.agree) {
    std::fprintf(stderr, "dicesim: failed: toss %lld in the log and its re-simulation disagree\n",
                 static_cast<long long>(a.toss));
    return kExitFailed;
  }
  return kExitOk;
}

}  // namespace

void register_replay(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* cmd = app.add_subcommand(
      "replay",
      "Recompute a recorded run from its LCM event log alone (written by `dicesim record` or the stock\n"
      "lcm-logger): the run's description comes from its run_start message, its results are fed to the\n"
      "aggregator's own code, and the same table / JSON as the live run is printed, with identical\n"
      "counts. --live also re-publishes every event at the recorded pace, so that a running recorder,\n"
      "bridge or lcm-spy sees the run again. --toss I prints toss I's logged bounces and re-simulates it.\n"
      "A truncated, corrupt or incomplete log is bad input (exit 2).\n\n"
      "Examples:\n"
      "  dicesim replay run.lcmlog\n"
      "  dicesim replay run.lcmlog --json\n"
      "  dicesim replay run.lcmlog --live --speed 4 --lcm 'udpm://239.255.76.67:7667?ttl=0'\n"
      "  dicesim replay run.lcmlog --toss 1000     # a traced toss (aggregate/run --trace-every 1000)\n"
      "  dicesim replay run.lcmlog --key-file run.key   # the log of an authenticated run");
  cmd->add_option("LOG", args->path, "The LCM event log")->required();
  cmd->add_option("--run", args->run, "The run to replay when the log holds several (default: the first)")
      ->type_name("ID")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--json", args->json, "Print exactly one JSON object on stdout (the shape of `dicesim toss --json`)");
  cmd->add_flag("--live", args->live, "Also re-publish every event on LCM at the recorded pace");
  cmd->add_option("--lcm", args->lcm,
                  "With --live: LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0)")
      ->type_name("URL");
  cmd->add_option("--speed", args->speed, "With --live: pace factor (2: twice as fast as recorded)")
      ->type_name("X")
      ->capture_default_str()
      ->check(CLI::Range(1e-3, 1e6));
  add_key_file_option(cmd, args->key_file)
      ->description("The log of an authenticated run: use only messages whose HMAC-SHA-256 seal opens with the key\n"
                    "in FILE (the rest, e.g. forgeries heard on the bus, are counted and dropped). --live\n"
                    "re-publishes the events as recorded, seals included. README, Security");
  cmd->add_option("--toss", args->toss, "Print toss I's bounces from the log and re-simulate it (exit 1 if they differ)")
      ->type_name("I")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args, &exit_code] {
    std::signal(SIGINT, on_stop_signal);
    std::signal(SIGTERM, on_stop_signal);
    try {
      exit_code = args->toss >= 0 ? replay_toss(*args) : replay_run(*args);
    } catch (const eventlog::LogError& e) {
      std::fprintf(stderr, "dicesim: error: %s\n", e.what());
      exit_code = kExitBadInput;
    }
  });
}

}  // namespace dicesim

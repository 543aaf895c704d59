// dicesim aggregate: start a distributed run over LCM, collect it, print it as `toss` does.
// Also the aggregating half of `dicesim run` (aggregate_and_report).
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <thread>
#include <csignal>
#include <cstdio>

#include <spdlog/spdlog.h>

#include "aggregator/checkpoint.hpp"
#include "sim/body/outcome.hpp"
#include "aggregator/session.hpp"
#include "aggregator/target.hpp"
#include "apps/commands.hpp"
#include "apps/interrupt.hpp"
#include "sim/scene/scene_hash.hpp"
#include "apps/fidelity_name.hpp"
#include "apps/progress.hpp"
#include "apps/report.hpp"
#include "logger/log.hpp"
#include "messages/run_spec.hpp"
#include "messages/spec_scene.hpp"
#include "messages/wire.hpp"
#include "sim/body/die_model.hpp"
#include "sim/models/compile.hpp"
#include "sim/study/auto_pilot.hpp"

namespace dicesim {
namespace {

// With a target and no explicit --tosses, the run may go this far.
constexpr std::uint64_t kTargetCap = 1'000'000'000;

}  // namespace

void AggregateArgs::add_to(CLI::App* cmd) {
  scene.add_to(cmd);
  cmd->add_option("--lcm", lcm,
                  "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0, which never leaves this host)")
      ->type_name("URL");
  tosses_opt = cmd->add_option("-n,--tosses", tosses, "Number of tosses (default 100000). With --target-halfwidth: the most it may take when\n"
                                     "given; without -n, as many as the target needs (up to 10^9).\n"
                                     "Any exact whole number: 100000, 1e5, 100_000")
                   ->check(CLI::Range(1ULL, 1ULL << 40));
  cmd->add_option("--seed", seed, "Run seed (with the toss index, the only source of randomness)")->capture_default_str();
  cmd->add_option("--trace-every", trace_every,
                  "Publish every impact of every K-th toss on DICESIM_BOUNCE_STATE (0: none)")
      ->type_name("K")
      ->capture_default_str()
      ->check(CLI::Range(0, 1 << 30));
  cmd->add_option("--target-halfwidth", target_halfwidth,
                  "Stop when every face's 95% half-width is <= H (judged every 10000 tosses, in index order:\n"
                  "the same stopping point as `dicesim toss --target-halfwidth H`)")
      ->type_name("H")
      ->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--timeout", timeout_s, "Fail (exit 1) if the run has not finished after this many seconds (0: never)")
      ->type_name("S")
      ->check(CLI::Range(0.0, 1e9));
  cmd->add_flag("--json", json, "Print exactly one JSON object on stdout (the shape of `dicesim toss --json`)");
  add_key_file_option(cmd, key_file);
}

void AggregateArgs::add_checkpoint_options(CLI::App* cmd) {
  cmd->get_option("SCENE")->required(false);  // --resume takes the scene from the checkpoint
  cmd->add_option("--checkpoint", checkpoint,
                  "Write the run's state to FILE at most once a second and at the end (atomic: write, fsync,\n"
                  "rename, fsync the directory), so that `--resume FILE` can continue it after a crash")
      ->type_name("FILE");
  cmd->add_option("--resume", resume,
                  "Continue the run saved in FILE (same run id, scene, seed and size; the workers still\n"
                  "serving it carry on) instead of starting one; give no SCENE. Checkpoints go on to FILE\n"
                  "(or to --checkpoint). Workers stop serving a run after 5 s without its aggregator\n"
                  "(`worker --once` then exits; others take it up again when it comes back)")
      ->type_name("FILE");
}

// The model of a checkpoint's run, rebuilt as a worker would; it must be the one the run started with.
DieModel rebuild_checkpoint_model(const agg::Checkpoint& ck, const std::string& path) {
  const wire::RunSpec spec = wire::from_message(ck.start);
  DieModel model = wire::compile_spec(spec);
  if (wire::model_fingerprint(model) != spec.fingerprint || model.outcome_labels != ck.labels)
    throw std::runtime_error("checkpoint '" + path + "': this dicesim build compiles the run's scene to a different model "
                             "(fingerprint): resume it with the build that started it");
  return model;
}

PreparedRun prepare_run(const AggregateArgs& a, std::int64_t run_id) {
  // Bad input fails here, before anything is published (SceneError -> exit 2 in run_cli).
  DieModel model = compile(a.scene.load(), a.scene.path);
  std::vector<std::string> overrides = a.scene.overrides;  // as SceneArgs::load composes them
  check_fidelity_name(a.scene.fidelity);
  if (!a.scene.fidelity.empty()) overrides.push_back("sim.fidelity=\"" + a.scene.fidelity + "\"");
  const std::uint64_t total = a.target_halfwidth > 0 && a.tosses_opt && a.tosses_opt->count() == 0 ? kTargetCap : a.tosses;
  // auto: the pilot runs here, once; the workers are told the model it chose (an override), so
  // every process tosses the same model without a pilot of its own.
  resolve_auto(model, a.target_halfwidth > 0 ? precision_of_target(model, a.target_halfwidth) : precision_of_run(model, a.tosses),
               static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  if (model.fidelity_requested == Fidelity::Auto)
    overrides.push_back(std::string("sim.fidelity=\"") + to_string(model.fidelity) + "\"");
  wire::RunSpec spec = wire::make_run_spec(run_id != 0 ? run_id : wire::new_run_id(), a.scene.path, overrides, model, a.seed,
                                           total, a.trace_every);
  return {std::move(model), std::move(spec)};
}

int aggregate_and_report(const AggregateArgs& a, const std::string& url, std::int64_t run_id, int workers,
                         const std::function<std::string()>& on_tick, const std::atomic<bool>* cancel,
                         const PreparedRun* prepared, const std::function<void()>& on_session_end) {
  std::optional<agg::Checkpoint> resume;
  if (!a.resume.empty()) {
    if (!a.scene.path.empty() || !a.scene.overrides.empty() || !a.scene.fidelity.empty())
      throw CLI::ValidationError("--resume", "continues the checkpoint's run: give no SCENE, --set or --fidelity");
    resume = agg::read_checkpoint(a.resume);  // CheckpointError -> exit 2
  } else if (a.scene.path.empty()) {
    throw CLI::RequiredError("SCENE (or --resume FILE)");
  }
  agg::AggregatorConfig cfg;
  cfg.key = load_run_key(a.key_file);  // KeyError -> exit 2, before anything is published
  std::optional<PreparedRun> compiled;
  if (!resume && !prepared) compiled = prepare_run(a, run_id);
  const DieModel model = resume ? rebuild_checkpoint_model(*resume, a.resume) : prepared ? prepared->model : compiled->model;
  if (resume) {
    cfg.spec = wire::from_message(resume->start);
    cfg.target_halfwidth = resume->target_halfwidth;
  } else {
    cfg.spec = prepared ? prepared->spec : compiled->spec;
    cfg.target_halfwidth = a.target_halfwidth;
  }
  const wire::RunSpec& spec = cfg.spec;
  logging::set_run_id(spec.run_id);
  // The provenance the answer carries on the wire (every probabilities message) and in the report:
  // the user's scene, overrides and hash as `toss` reports them (auto's choice travels to the
  // workers as one more override, prepare_run, which is how the run was made, not what was asked).
  // A resumed run has only the checkpoint's spec. threads: the workers `run` started; 0 for
  // `aggregate`, whose workers come from elsewhere (the report counts the most seen at once).
  const auto run_provenance = [&](int threads) {
    return resume ? make_provenance(spec.origin, spec.overrides, wire::spec_scene_sha256(spec), model, spec.seed, spec.total, threads)
                  : make_provenance(a.scene.path, a.scene.applied_overrides(),
                                    scene_sha256(a.scene.path, a.scene.applied_overrides()), model, spec.seed, spec.total, threads);
  };
  cfg.provenance = provenance_json(run_provenance(workers)).dump();

  ProgressBar bar;
  std::size_t refusals_shown = 0;
  int most_workers = 0;
  double idle_since = -1.0, last_hint = -1e9;
  const auto t0 = std::chrono::steady_clock::now();
  agg::SessionOptions opt;
  opt.url = url;
  opt.cancel = cancel;
  opt.resume = resume ? &*resume : nullptr;
  opt.checkpoint_path = a.checkpoint.empty() ? a.resume : a.checkpoint;
  if (!opt.checkpoint_path.empty()) {
    // A checkpoint that cannot be written would only be noticed after a crash: bad input now.
    std::string dir = std::filesystem::path(opt.checkpoint_path).parent_path().string();
    if (dir.empty()) dir = ".";
    if (std::filesystem::is_directory(opt.checkpoint_path) || ::access(dir.c_str(), W_OK | X_OK) != 0)
      throw CLI::ValidationError("--checkpoint", "cannot write the checkpoint '" + opt.checkpoint_path +
                                                     "' (its directory '" + dir + "' must exist and be writable)");
  }
  if (!cfg.key.empty()) spdlog::info("authenticated run: every message is sealed and checked with HMAC-SHA-256 ({})", a.key_file);
  opt.on_start = [&](const agg::Aggregator& agg) {
    const agg::ResumeInfo& r = agg.resume_info();
    if (!r.resumed) return;
    spdlog::info("resumed run {} from '{}' (checkpoint {:.1f} s old, resume #{}): {} of {} tosses held, {} leases kept "
                 "for their workers, {} tosses to lease again",
                 spec.run_id, a.resume, r.age_s, r.resumes, r.held, spec.total, r.leases, r.requeued);
  };
  opt.on_tick = [&](const agg::Aggregator& agg) -> std::string {
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    bar.update(agg.received(), agg.total());
    most_workers = std::max(most_workers, agg.live_workers());
    for (; refusals_shown < agg.refusals().size(); ++refusals_shown)
      spdlog::warn("{}", agg.refusals()[refusals_shown]);
    if (agg.live_workers() > 0) {
      idle_since = -1.0;
    } else if (idle_since < 0) {
      idle_since = now;
    } else if (workers == 0 && now - idle_since > 5.0 && now - last_hint > 30.0) {
      last_hint = now;
      spdlog::info("waiting for workers on {} (start some: dicesim worker --lcm '{}')", url, url);
    }
    if (a.timeout_s > 0 && now > a.timeout_s)
      return "timed out after " + std::to_string(a.timeout_s) + " s with " + std::to_string(agg.received()) + " of " +
             std::to_string(agg.total()) + " tosses";
    // A run that is over is not failed by what the caller sees next (run's workers exit as soon as
    // they hear the end, possibly before this tick). (Found by helper "tail3" under load.)
    return on_tick && !agg.finished() ? on_tick() : std::string();
  };
  const agg::SessionResult res = agg::run_session(opt, cfg);
  if (on_session_end) on_session_end();
  bar.finish();
  // The health line (tests/integration greps it) is a log line: info, with the run's context.
  spdlog::info("run {}: {}", spec.run_id, agg::health_line(res.health));
  if (!opt.checkpoint_path.empty()) {
    // Checkpoint cost (bench: the checkpoint target is <= 1% of the run time).
    const double run_s = std::max(1e-9, res.elapsed_s);
    spdlog::info("checkpoint '{}': {} snapshots taking {:.1f} ms in the aggregator loop ({:.3f}% of {:.2f} s, max {:.2f} ms); "
                 "{} writes, {:.1f} ms in the writer thread (write+fsync+rename+fsync, max {:.1f} ms){}",
                 opt.checkpoint_path, res.snapshots, 1e3 * res.snapshot_s, 100.0 * res.snapshot_s / run_s, res.elapsed_s,
                 1e3 * res.max_snapshot_s, res.writer.writes, 1e3 * res.writer.write_s, 1e3 * res.writer.max_write_s,
                 res.writer.error.empty() ? "" : "; LAST WRITE FAILED: " + res.writer.error);
  }
  if (res.end == agg::SessionEnd::Cancelled) {
    std::fprintf(stderr, "dicesim: interrupted\n");
    return kExitFailed;
  }
  if (res.end == agg::SessionEnd::Failed) {
    std::fprintf(stderr, "dicesim: failed: %s\n", res.error.c_str());
    return kExitFailed;
  }
  if (a.target_halfwidth > 0) {
    const bool reached = agg::halfwidth_reached(res.counts, a.target_halfwidth);
    std::fprintf(stderr, "dicesim: target half-width %g %s after %llu tosses (widest: %.5f)\n", a.target_halfwidth,
                 reached ? "reached" : "NOT reached", static_cast<unsigned long long>(res.tosses),
                 agg::max_halfwidth(res.counts));
  }

  RunReport r;
  r.scene = spec.origin;
  r.fidelity = spec.fidelity;
  r.seed = spec.seed;
  r.threads = workers > 0 ? workers : std::max(1, most_workers);
  r.tosses = res.tosses;
  r.counts = res.counts;
  set_labels(r, model);
  // auto: the pilot's numbers as `toss` reports them (prepare_run resolved the model; the pilot is a
  // function of the scene and the run's size, so running it again gives the same numbers).
  if (!resume && model.fidelity_requested == Fidelity::Auto) {
    DieModel again = model;
    r.pilot = resolve_auto(again, a.target_halfwidth > 0 ? precision_of_target(again, a.target_halfwidth) : precision_of_run(again, a.tosses),
                           static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  }
  r.elapsed_s = res.run_elapsed_s;
  r.provenance = run_provenance(r.threads);
  print_report(r, a.json);
  return kExitOk;
}

void register_aggregate(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<AggregateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "aggregate",
      "Start a distributed run over LCM and collect it: announce the scene, lease index ranges to\n"
      "every `dicesim worker` on the bus, drop duplicates, re-lease what got lost, publish running\n"
      "probabilities on DICESIM_PROBABILITIES, and print the same table / JSON as `dicesim toss`\n"
      "(identical counts for the same scene, fidelity, seed and N).\n\n"
      "Examples:\n"
      "  dicesim worker & dicesim worker &\n"
      "  dicesim aggregate scenes/paper/die1.toml --tosses 1000000\n"
      "  dicesim aggregate scenes/paper/die2.toml --seed 7 --json --lcm 'udpm://239.255.76.67:7667?ttl=1'\n"
      "  dicesim aggregate scenes/fair.toml --target-halfwidth 0.002 --trace-every 1000\n"
      "  dicesim aggregate scenes/paper/die1.toml -n 100000000 --checkpoint run.ckpt   # then, after a crash:\n"
      "  dicesim aggregate --resume run.ckpt\n"
      "  dicesim aggregate scenes/paper/die1.toml --key-file run.key   # workers: dicesim worker --key-file run.key");
  args->add_to(cmd);
  args->add_checkpoint_options(cmd);
  cmd->callback([args, &exit_code] {
    std::signal(SIGINT, on_stop_signal);
    std::signal(SIGTERM, on_stop_signal);
    exit_code = aggregate_and_report(*args, wire::resolve_url(args->lcm), 0, 0, {}, &g_stop);
  });
}

}  // namespace dicesim

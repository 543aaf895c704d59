// dicesim show: the die (and one toss) as a self-contained HTML page (web/).
#include <cerrno>
#include <stdexcept>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "apps/commands.hpp"
#include "apps/info_json.hpp"
#include "sim/body/material_parts.hpp"
#include "sim/models/compile.hpp"
#include "sim/scene/scene_error.hpp"
#include "web/show_data.hpp"
#include "web/show_page.hpp"

namespace dicesim {
namespace {

struct ShowArgs {
  SceneArgs scene;
  std::int64_t toss = -1;
  CLI::Option* toss_opt = nullptr;
  std::uint64_t seed = 1;
  std::uint64_t tosses = 100000;
  std::string output;
};

int run_show(const ShowArgs& a) {
  const SceneDef def = a.scene.load();
  const bool with_toss = a.toss_opt->count() > 0;
  if (with_toss && (a.toss < 0 || static_cast<std::uint64_t>(a.toss) >= a.tosses))
    throw SceneError("dicesim show", "--toss", std::to_string(a.toss),
                     "outside the run's toss indices 0.." + std::to_string(a.tosses - 1) + " (--tosses " +
                         std::to_string(a.tosses) + ")");
  if (!def.dice.empty() || !def.obstacles.empty())
    throw SceneError(a.scene.path, def.dice.empty() ? "obstacles" : "dice", "(given)",
                     "dicesim show draws one die alone: a toss of several dice or among obstacles cannot be drawn yet "
                     "(docs/world.md)");
  std::string out = a.output;
  if (out.empty()) {
    out = std::filesystem::path(a.scene.path).stem().string();
    if (with_toss) out += "-toss-" + std::to_string(a.toss);
    out += ".html";
  }
  // Opened before the work: an unwritable path is bad input, found at once.
  std::ofstream file;
  if (out != "-") {
    file.open(out, std::ios::binary | std::ios::trunc);
    if (!file) throw SceneError("dicesim show", "-o", out, std::string("cannot be written: ") + std::strerror(errno));
  }
  const DieModel m = compile(def, a.scene.path);
  nlohmann::json page;
  page["scene"] = a.scene.path;
  page["die"] = web::die_json(m, def);
  page["info"] = info_json(a.scene.path, m, material_parts(def, a.scene.path));
  if (with_toss) page["toss"] = web::toss_json(m, a.seed, static_cast<std::uint64_t>(a.toss));
  const std::string html = web::show_html(page);
  if (out == "-") {
    std::fwrite(html.data(), 1, html.size(), stdout);
    return kExitOk;
  }
  file << html;
  file.close();
  if (!file) throw std::runtime_error("writing " + out + " failed");
  std::fprintf(stderr, "dicesim: wrote %s (%.2f MB); open it in any browser (it needs no network)\n", out.c_str(),
               static_cast<double>(html.size()) / 1e6);
  if (with_toss) {
    const auto& t = page["toss"];
    std::fprintf(stderr, "dicesim: toss %lld (seed %llu, %s): %s, outcome %s, %d impacts, %.3f s\n",
                 static_cast<long long>(a.toss), static_cast<unsigned long long>(a.seed),
                 t["fidelity"].get<std::string>().c_str(), t["status"].get<std::string>().c_str(),
                 t["outcome"].get<std::string>().empty() ? "-" : t["outcome"].get<std::string>().c_str(), t["bounces"].get<int>(),
                 t["t_end"].get<double>());
  }
  return kExitOk;
}

}  // namespace

void register_show(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ShowArgs>();
  CLI::App* cmd = app.add_subcommand(
      "show",
      "Write one self-contained HTML page (three.js inlined: opens offline in any browser) showing\n"
      "the die in 3-D: turnable, every face with its label, regions of other materials tinted,\n"
      "the centre of mass marked (red; the geometric centre grey), and `info`'s table beside it.\n"
      "With --toss I: toss number I of a run with --seed S (the very toss `toss`, `run` and\n"
      "Python's toss_one make), animated: play/pause, speed, a time slider, every impact on the\n"
      "timeline (time, corner/edge/face/rim, energy before and after), the face read highlighted\n"
      "and the outcome named. Flights between impacts are exact (sampled every 1 ms).\n\n"
      "Examples:  dicesim show scenes/dice/loaded-d20.toml\n"
      "           dicesim show scenes/dice/d20.toml --fidelity impulse --toss 7 -o d20-toss.html");
  args->scene.add_to(cmd);
  args->toss_opt = cmd->add_option("--toss", args->toss, "Animate toss number I (0 <= I < --tosses)");
  cmd->add_option("--seed", args->seed, "The run's seed (with --toss)")->capture_default_str();
  cmd->add_option("--tosses", args->tosses, "The run's size: the range --toss must fall in")->capture_default_str()->check(
      CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 62));
  cmd->add_option("-o,--output", args->output,
                  "The HTML file to write (default: SCENE's name[-toss-I].html here; '-' for stdout)");
  cmd->callback([args, &exit_code] { exit_code = run_show(*args); });
}

}  // namespace dicesim

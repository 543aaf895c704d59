// What the binding files of the `dicesim` Python module share: the Scene object and the way a long
// computation runs with the GIL released while Ctrl-C and `progress` still work.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/pybind11.h>

#include "sim/body/die_model.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim::py {

namespace pb = pybind11;

// A loaded scene: where it came from (a path, or TOML text with a name), its overrides, and the
// compiled model. Models at other fidelities are compiled on first use and kept.
class Scene {
 public:
  static std::shared_ptr<Scene> from_path(std::string path, std::vector<std::string> overrides);
  static std::shared_ptr<Scene> from_text(std::string text, std::string origin, std::vector<std::string> overrides);

  // The path as given, or the origin name of a scene from text: what reports call "scene".
  const std::string& origin() const { return origin_; }
  const std::vector<std::string>& overrides() const { return overrides_; }
  const SceneDef& def() const { return def_; }
  bool from_file() const { return !text_.has_value(); }

  // The scene's own model (fidelity = nullopt) or the one at `fidelity`, exactly as the CLI's
  // `--fidelity F` compiles it (the override sim.fidelity="F"; a bad name is a SceneError).
  std::shared_ptr<const DieModel> model(const std::optional<std::string>& fidelity = std::nullopt);

  // Loads the scene again with more overrides after its own (sweeps): as `--set` on the CLI.
  SceneDef load_with(const std::vector<std::string>& extra) const;
  // The SHA-256 of the scene load_with(extra) loads (provenance: sim/scene/scene_hash.hpp).
  std::string sha256_with(const std::vector<std::string>& extra) const;

 private:
  std::string origin_;
  std::optional<std::string> text_;
  std::vector<std::string> overrides_;
  SceneDef def_;
  std::shared_ptr<const DieModel> model_;
  std::map<std::string, std::shared_ptr<const DieModel>> by_fidelity_;
};

// A `scene=` argument: a Scene, or a path (str or os.PathLike) loaded as load_scene(path) would.
std::shared_ptr<Scene> scene_arg(const pb::handle& scene);
// A count argument such as `n=`: an int, or a float that is an exact whole number (1e4); None ->
// nullopt. A TypeError/ValueError naming `name` and the value otherwise.
std::optional<std::uint64_t> count_arg(const pb::handle& n, const char* name);
// The `fidelity=` argument as the CLI's --fidelity override text. A name that is not a fidelity is
// a ValueError naming it and the choices.
std::vector<std::string> fidelity_override(const std::optional<std::string>& fidelity);

// Progress shared between the computing thread (writes) and the Python thread (reads).
struct RunMonitor {
  std::atomic<bool> cancel{false};
  std::atomic<std::uint64_t> done{0}, total{0};
  void report(std::uint64_t d, std::uint64_t t) {
    total.store(t, std::memory_order_relaxed);
    done.store(d, std::memory_order_relaxed);
  }
};

// Runs `work` on a C++ thread while the calling Python thread waits with the GIL released. Every
// 20 ms it takes the GIL back to check for signals (Ctrl-C: KeyboardInterrupt) and, about every
// 100 ms, to call `progress(done, total)` if it is not None. On an exception there (or in
// `progress`) it sets monitor.cancel, waits for `work` to stop (it must poll the flag), and
// rethrows. Exceptions of `work` itself are rethrown here. Call with the GIL held.
void run_interruptible(const std::function<void()>& work, RunMonitor& monitor, const pb::object& progress);

// Number of threads for `threads=0`: all cores, as the CLI's default.
int resolve_threads(int threads);

// Registration of each part of the module (module.cpp calls them in order).
void register_scene(pb::module_& m);
void register_toss(pb::module_& m);
void register_trace(pb::module_& m);
void register_fit(pb::module_& m);  // fit_binding.cpp
void register_power(pb::module_& m);  // power_binding.cpp

}  // namespace dicesim::py

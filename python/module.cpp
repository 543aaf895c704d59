// The `dicesim` Python module: scenes, Monte Carlo runs, single tosses with their impacts, sweeps,
// over the same C++ library as the `dicesim` command line (not a wrapper around it).
#include <algorithm>
#include <chrono>
#include <exception>
#include <future>
#include <thread>

#include "python/bindings.hpp"
#include "sim/scene/scene_error.hpp"

namespace dicesim::py {

void register_show(pb::module_& m);  // show_binding.cpp

int resolve_threads(int threads) {
  if (threads < 0) throw pb::value_error("threads must be >= 0 (0: all cores), got " + std::to_string(threads));
  if (threads > 1024) throw pb::value_error("threads must be <= 1024, got " + std::to_string(threads));
  // hardware_concurrency() reads /sys on every call (tens of microseconds): once per process.
  static const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return threads == 0 ? cores : threads;
}

void run_interruptible(const std::function<void()>& work, RunMonitor& monitor, const pb::object& progress) {
  using namespace std::chrono_literals;
  std::future<void> running = std::async(std::launch::async, work);
  // Stops the computation and waits for it (without the GIL: its threads never need it).
  auto stop = [&] {
    monitor.cancel = true;
    pb::gil_scoped_release nogil;
    running.wait();
  };
  auto last_progress = std::chrono::steady_clock::now();
  for (;;) {
    bool finished;
    {
      pb::gil_scoped_release nogil;
      finished = running.wait_for(20ms) == std::future_status::ready;
    }
    if (finished) break;
    if (PyErr_CheckSignals() != 0) {  // only the main thread sees signals; elsewhere this is 0
      stop();
      throw pb::error_already_set();
    }
    const auto now = std::chrono::steady_clock::now();
    if (!progress.is_none() && now - last_progress >= 100ms) {
      last_progress = now;
      try {
        progress(monitor.done.load(), monitor.total.load());
      } catch (...) {
        stop();
        throw;
      }
    }
  }
  running.get();  // rethrows what `work` threw
  if (!progress.is_none()) progress(monitor.done.load(), monitor.total.load());
}

}  // namespace dicesim::py

PYBIND11_MODULE(dicesim, m) {
  namespace py = dicesim::py;
  namespace pb = pybind11;
  m.doc() =
      "dicesim: how likely is each face of a real, possibly unfair die?\n\n"
      "Simulates physical tosses (flight, bounces, rest) of a die of any density layout with the\n"
      "same C++ library as the `dicesim` command line: the same scene, fidelity, seed and number of\n"
      "tosses give the same counts here and there, on any number of threads.\n\n"
      "    import dicesim\n"
      "    scene = dicesim.load_scene(\"scenes/paper/die1.toml\")\n"
      "    r = dicesim.toss(scene, 100_000)\n"
      "    r.labels, r.counts, r.p, r.ci95    # numpy arrays, faces by label\n"
      "    r.to_dict()                        # exactly `dicesim toss --json`'s object\n\n"
      "Functions: load_scene, scene_from_toml, toss, toss_one, show, sweep, sweep_file, fit, power. Bad scene\n"
      "input raises SceneError (a ValueError) with the message the command line prints.";
  m.attr("__version__") = "0.1.0";

  // SceneError: a ValueError carrying the CLI's exit-2 message and its parts.
  static pb::exception<dicesim::SceneError> scene_error(m, "SceneError", PyExc_ValueError);
  scene_error.attr("__doc__") =
      "Bad scene input: a missing file, an unknown key, a wrong type, a value out of range.\n"
      "str(e) is the message `dicesim` prints after 'dicesim: error: ' (exit code 2); the parts are\n"
      "in e.file, e.key, e.value and e.allowed.";
  pb::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const dicesim::SceneError& e) {
      pb::object err = pb::handle(scene_error.ptr())(e.what());  // an instance, to carry the parts
      err.attr("file") = e.file();
      err.attr("key") = e.key();
      err.attr("value") = e.value();
      err.attr("allowed") = e.allowed();
      PyErr_SetObject(scene_error.ptr(), err.ptr());
    }
  });

  py::register_scene(m);
  py::register_toss(m);
  py::register_trace(m);
  py::register_show(m);
  py::register_fit(m);
  py::register_power(m);
}

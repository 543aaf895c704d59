// Ctrl-C and SIGTERM during a long command (toss, sweep, fit, power): the first signal sets a flag
// that the run polls as its cancel flag; the command then prints what is done, marked partial, and
// exits 130. A second signal acts as it would without us (the handler resets itself): it kills.
#pragma once

#include <atomic>

namespace dicesim {

inline constexpr int kExitInterrupted = 130;  // as a shell reports a process killed by SIGINT

// Installs the handlers for its lifetime (the previous ones come back after).
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  // Set by the first SIGINT/SIGTERM: give it to RunConfig::cancel (and the like).
  static const std::atomic<bool>* flag();
  static bool interrupted() { return flag()->load(); }
};

// The bus commands (aggregate, bridge, record, replay, run, serve, watch, worker) run until
// stopped instead: they install on_stop_signal for SIGINT and SIGTERM and poll g_stop. One flag
// for all of them (a process runs one command), defined once, so that apps/ builds as one unity
// file too (apps/CMakeLists.txt).
extern std::atomic<bool> g_stop;
void on_stop_signal(int);

}  // namespace dicesim

// A progress bar on stderr for runs longer than a second: redrawn in place on a terminal,
// an occasional plain line otherwise (logs, CI). Never touches stdout.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>

#include <unistd.h>

namespace dicesim {

class ProgressBar {
 public:
  explicit ProgressBar(bool enabled = true) : enabled_(enabled), tty_(isatty(STDERR_FILENO) != 0) {}
  ~ProgressBar() { finish(); }

  void update(std::uint64_t done, std::uint64_t total) {
    if (!enabled_ || total == 0) return;
    std::lock_guard lock(mu_);
    const double t = seconds();
    if (t < 1.0) return;
    if (done == last_done_) return;  // nothing new (the final count is reported twice)
    if (!tty_ && t - last_line_ < 10.0 && done < total) return;
    last_line_ = t;
    last_done_ = done;
    const double frac = static_cast<double>(done) / static_cast<double>(total);
    const double rate = static_cast<double>(done) / t;
    const double eta = rate > 0 ? static_cast<double>(total - done) / rate : 0.0;
    constexpr int kWidth = 30;
    char bar[kWidth + 1];
    const int filled = static_cast<int>(frac * kWidth);
    for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '#' : '.';
    bar[kWidth] = '\0';
    std::fprintf(stderr, "%s[%s] %5.1f%%  %llu/%llu  %.0f tosses/s  ETA %.0f s%s", tty_ ? "\r" : "", bar,
                 100.0 * frac, static_cast<unsigned long long>(done), static_cast<unsigned long long>(total), rate,
                 eta, tty_ ? "   " : "\n");
    std::fflush(stderr);
    drawn_ = true;
  }

  void finish() {
    std::lock_guard lock(mu_);
    if (drawn_ && tty_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  bool enabled_, tty_;
  bool drawn_ = false;
  double last_line_ = 0.0;
  std::uint64_t last_done_ = ~std::uint64_t{0};
  std::mutex mu_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace dicesim

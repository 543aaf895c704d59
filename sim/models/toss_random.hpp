// Counter-based randomness: toss i of a run draws only from Philox4x32-10 keyed by the run's
// seed, with the toss index in the counter. No state is shared between tosses, so any split of
// the indices over threads, processes or machines gives the same numbers.
#pragma once

#include <Random123/philox.h>

#include <cmath>
#include <cstdint>

#include "sim/log.hpp"
#include "sim/math.hpp"
#include "sim/sincos.hpp"

namespace dicesim {

class TossRandom {
 public:
  TossRandom(std::uint64_t seed, std::uint64_t toss) {
    key_ = {{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)}};
    ctr_ = {{static_cast<std::uint32_t>(toss), static_cast<std::uint32_t>(toss >> 32), 0u, 0u}};
  }

  // Uniform on the open interval (0, 1), 53 random bits.
  double uniform() {
    if (left_ == 0) refill();
    --left_;
    return buf_[left_];
  }

  // Standard normal (Box-Muller; the pair's second value is kept for the next call). The
  // logarithm and the sine and cosine are this project's own (sim/log.hpp, sim/sincos.hpp): libm's
  // pick a variant by CPU at run time, and a draw must be the same on every worker's machine.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double r = std::sqrt(-2.0 * log_fixed(uniform()));
    const SinCos a = sincos_turns(uniform());  // the angle 2 pi u
    spare_ = r * a.sin;
    has_spare_ = true;
    return r * a.cos;
  }

 private:
  void refill() {
    r123::Philox4x32 gen;
    const auto out = gen(ctr_, key_);
    ++ctr_.v[2];  // next block of this toss
    buf_[0] = to_unit(out.v[0], out.v[1]);
    buf_[1] = to_unit(out.v[2], out.v[3]);
    left_ = 2;
  }
  static double to_unit(std::uint32_t a, std::uint32_t b) {
    const std::uint64_t bits = (static_cast<std::uint64_t>(a >> 5) << 26) | (b >> 6);  // 53 bits
    return (static_cast<double>(bits) + 0.5) * 0x1.0p-53;
  }

  r123::Philox4x32::key_type key_;
  r123::Philox4x32::ctr_type ctr_;
  double buf_[2] = {0.0, 0.0};
  int left_ = 0;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace dicesim

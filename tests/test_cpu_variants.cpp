// The toss's own elementary functions (sim/log.hpp, sim/atan.hpp, sim/sincos.hpp) against glibc's,
// whose FMA and non-FMA variants are picked by CPU at run time and differ in the last bit for some
// arguments: this test binary runs again in a child whose glibc is told the CPU has no FMA/AVX2
// (GLIBC_TUNABLES), and both must compute the same bits.
#include <gtest/gtest.h>

#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "sim/atan.hpp"
#include "sim/models/toss_random.hpp"

namespace dicesim {
namespace {

struct Hashes {
  std::uint64_t draws = 1469598103934665603ULL, atan = 1469598103934665603ULL;
  std::uint64_t libm_log = 1469598103934665603ULL, libm_atan = 1469598103934665603ULL;
};

void mix(std::uint64_t& h, double v) { h = (h ^ std::bit_cast<std::uint64_t>(v)) * 1099511628211ULL; }

// 2*10^5 tosses' first six normal draws through TossRandom, the arc tangent over the range the
// asymmetric top's precession integral uses (sqrt E, E >= 2e-3), and libm's log and atan of the
// same arguments (the controls).
Hashes hashes() {
  Hashes h;
  for (std::uint64_t t = 0; t < 200000; ++t) {
    TossRandom normals(20261122, t), uniforms(20261122, t);
    for (int k = 0; k < 6; ++k) {
      mix(h.draws, normals.normal());
      mix(h.libm_log, std::log(uniforms.uniform()));
    }
    const double x = 0.04 + static_cast<double>(t) * 1.37e-4;
    mix(h.atan, atan_fixed(x));
    mix(h.libm_atan, std::atan(x));
  }
  return h;
}

// (With std::log in TossRandom this test failed.)
TEST(CpuVariants, TheTossComputesTheSameBitsWhicheverLibmTheCpuSelects) {
  if (std::getenv("DICESIM_CPU_VARIANTS_CHILD")) {  // the child: print and stop
    const Hashes h = hashes();
    std::printf("hashes %llu %llu %llu %llu\n", static_cast<unsigned long long>(h.draws),
                static_cast<unsigned long long>(h.atan), static_cast<unsigned long long>(h.libm_log),
                static_cast<unsigned long long>(h.libm_atan));
    return;
  }
  if (!__builtin_cpu_supports("fma") || !__builtin_cpu_supports("avx2")) {
    if (std::getenv("CI") && std::string(std::getenv("CI")) == "true") FAIL() << "this CPU has no FMA/AVX2 variant to compare";
    GTEST_SKIP() << "no FMA/AVX2: glibc has only one variant here";
  }
  const Hashes here = hashes();
  const std::string cmd = "DICESIM_CPU_VARIANTS_CHILD=1 GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA,-FMA4,-AVX /proc/" +
                          std::to_string(::getpid()) +
                          "/exe --gtest_filter=CpuVariants.TheTossComputesTheSameBitsWhicheverLibmTheCpuSelects";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  char line[512];
  unsigned long long draws = 0, atan = 0, libm_log = 0, libm_atan = 0;
  bool found = false;
  while (std::fgets(line, sizeof line, p))
    if (std::sscanf(line, "hashes %llu %llu %llu %llu", &draws, &atan, &libm_log, &libm_atan) == 4) found = true;
  ASSERT_EQ(pclose(p), 0);
  ASSERT_TRUE(found) << cmd;
  // The controls: libm's own functions do change there, so the switch took effect.
  EXPECT_NE(libm_log, here.libm_log) << "libm's log gave the same bits without FMA: the switch did not take effect";
  EXPECT_NE(libm_atan, here.libm_atan) << "libm's atan gave the same bits without FMA";
  EXPECT_EQ(draws, here.draws) << "a toss's draws depend on the CPU";
  EXPECT_EQ(atan, here.atan) << "the precession angle depends on the CPU";
}

}  // namespace
}  // namespace dicesim

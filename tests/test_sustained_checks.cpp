// Deterministic checks of the sustained-contact phase against closed-form mechanics
// (tests/sustained_checks.hpp, issue 39 point 2). The tolerances are the issue's: a sliding block
// stops at v^2 / (2 mu g) within 0.5 %, Euler's disk precesses at the steady rate within 0.3 %; a
// die rocking about a sticking edge lands with the speed energy gives within 0.25 % (0.5 % of its
// kinetic energy, the sliding block's tolerance on an energy-derived length). The FixedStepper
// meets the sliding block (its COM's horizontal path with the step's mean velocity) and Euler's
// disk at the default steps, but not the rocking die at a polyhedron's 3 ms (first order in the
// rotation): that assertion is a DISABLED_ test (the leapfrog, sim.contact_tol, meets it: below);
// the enabled one holds the same tolerance at the finer step where the fixed stepper meets it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "sustained_checks.hpp"

using namespace dicesim;
using namespace dicesim::testing;

namespace {

constexpr double kDefault = 0.0;  // fixed_steps(0): the die's own contact_step

// Prints one check's relative error against the step with the observed order between successive
// steps, and returns the errors (coarsest first).
template <class F>
std::vector<double> table(const char* what, F check) {
  const std::vector<double> steps = {3e-3, 1e-3, 3e-4, 2e-4, 1e-4};
  std::printf("%s, FixedStepper as `impulse` runs it\n  step (ms)   measured      expected      rel. error    order   steps\n",
              what);
  std::vector<double> errors;
  double prev = 0.0, prev_h = 0.0;
  for (double h : steps) {
    const CheckResult r = check(fixed_steps(h));
    const double order =
        prev != 0.0 && r.rel_error != 0.0 ? std::log(std::abs(prev / r.rel_error)) / std::log(prev_h / h) : NAN;
    std::printf("  %8.2f  %12.7g  %12.7g  %+11.3e  %6.2f  %6ld\n", h * 1e3, r.measured, r.expected, r.rel_error, order,
                r.steps);
    errors.push_back(r.rel_error);
    prev = r.rel_error;
    prev_h = h;
  }
  return errors;
}

}  // namespace

// The error-vs-step tables (the report's main result; run with --gtest_filter=SustainedChecks.Tables
// to read them). Each check must converge: 30x finer steps at least 10x smaller error.
TEST(SustainedChecks, Tables) {
  const auto slide = table("sliding block (3 cm cube, v 1 m/s, mu 0.3): stop distance (m)",
                           [](const SustainedFactory& f) { return sliding_block(f); });
  const auto disk = table("Euler's disk (quarter, alpha 30 deg, 0.5 s): precession rate (rad/s)",
                          [](const SustainedFactory& f) { return euler_disk(f); });
  const auto rock = table("rocking die (3 cm cube, theta0 0.1 rad, mu 1): landing |omega| (rad/s)",
                          [](const SustainedFactory& f) { return static_cast<CheckResult>(rocking_die(f)); });
  for (const auto* e : {&slide, &disk, &rock}) EXPECT_LT(std::abs(e->back()), 0.1 * std::abs(e->front()));
}

// Each step removes mu g h of speed; with the COM moved by the step's end speed the distance came
// out short by v h / 2 (-mu g h / v: -0.88 % at 3 ms, -0.29 % at 1 ms). Moved by the step's mean
// speed (stepper_trial.cpp) it is exact but for the last step's stop inside it: +1.5e-5 at 3 ms,
// +1.4e-6 at 1 ms.
TEST(SustainedChecks, SlidingBlockStopsAtTheCoulombDistance) {
  const CheckResult r = sliding_block(fixed_steps(1e-3));
  EXPECT_LT(std::abs(r.rel_error), 0.005) << r.measured << " m against " << r.expected;
}
TEST(SustainedChecks, SlidingBlockAtTheDefaultStep) {  // -0.88 % at 3 ms with the end speed
  const CheckResult r = sliding_block(fixed_steps(kDefault));
  EXPECT_LT(std::abs(r.rel_error), 0.005) << r.measured << " m against " << r.expected;
}

// Today -0.12 % at 0.1 ms (30 deg), -1.2 % at the default 1 ms (the mean rate falls as the
// motion decays, so the error grows with the time measured: over the first 0.1 s it is -0.25 %
// at 1 ms); at 20 and 60 deg -0.12 % and -0.09 % at 0.1 ms (not run here: 2 s each).
TEST(SustainedChecks, EulersDiskPrecessesAtTheSteadyRate) {
  const CheckResult r = euler_disk(fixed_steps(1e-4));
  EXPECT_LT(std::abs(r.rel_error), 0.003) << r.measured << " rad/s against " << r.expected;
}
TEST(SustainedChecks, EulersDiskAtTheDefaultStep) {
  for (double alpha_deg : {20.0, 30.0, 60.0}) {
    const CheckResult r = euler_disk(fixed_steps(kDefault), alpha_deg * kPi / 180.0);
    std::printf("Euler's disk at the default step, %.0f deg: %.7g against %.7g rad/s (%+.3e)\n", alpha_deg, r.measured,
                r.expected, r.rel_error);
    EXPECT_LT(std::abs(r.rel_error), 0.003) << alpha_deg << " deg: " << r.measured << " rad/s against " << r.expected;
  }
}

// The wobbling disk's energy per second against the step, mu 0 and 2 (printed). Since a rim's
// steps are drift-kick-drift (rim_step.cpp), measured 2026-11-29 (lead): at 1 / 0.2 / 0.025 ms,
// mu 0: -1.5e-6 / -3.4e-8 / -2.1e-8 per second; mu 2: -3.4e-4 / -3.0e-6 / -1.5e-6 (second order to
// 0.05 ms, then rounding and the rim changes). The first-order steps lost -1.8e-2 / -4.1e-3 /
// -5.0e-4 (mu 0) and -2.3e-2 / -5.9e-3 / -8.5e-4 (mu 2).
TEST(SustainedChecks, WobblingDiskTable) {
  const std::vector<double> steps = {1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2.5e-5};
  std::printf("wobbling disk (quarter, 60 deg + 5 rad/s of spin, 0.3 s): energy change per second / E0\n  step (ms)   mu 0         mu 2\n");
  std::vector<double> loss[2];
  for (double h : steps) {
    const CheckResult a = wobbling_disk(fixed_steps(h), 0.0), b = wobbling_disk(fixed_steps(h), 2.0);
    std::printf("  %8.3f  %+11.3e  %+11.3e\n", h * 1e3, a.measured, b.measured);
    loss[0].push_back(a.measured);
    loss[1].push_back(b.measured);
  }
  for (const auto& l : loss) {
    for (double x : l) EXPECT_LT(x, 1e-6);  // never a gain beyond rounding
    EXPECT_LT(std::abs(l.back()), 0.1 * std::abs(l.front()));  // converges: 40x finer, >10x less
    EXPECT_LT(std::abs(l[2]), 1e-5);  // at the default 0.2 ms the step itself takes < 1e-5 a second
  }
}

// Today -0.08 % at 0.1 ms (theta0 0.1 rad; -0.18 % from 0.02 rad), -2.7 % at the default 3 ms.
TEST(SustainedChecks, RockingDieLandsWithTheSpeedEnergyGives) {
  for (double theta0 : {0.02, 0.1, 0.3}) {
    const RockingResult r = rocking_die(fixed_steps(1e-4), theta0);
    EXPECT_LT(std::abs(r.rel_error), 0.0025) << theta0 << " rad: " << r.measured << " rad/s against " << r.expected;
    EXPECT_LT(r.tilt_at_landing, 1e-3) << theta0;  // measured at the landing, not before it
  }
}
TEST(SustainedChecks, DISABLED_RockingDieAtTheDefaultStep) {
  for (double theta0 : {0.02, 0.1, 0.3}) {
    const RockingResult r = rocking_die(fixed_steps(kDefault), theta0);
    EXPECT_LT(std::abs(r.rel_error), 0.0025) << theta0 << " rad: " << r.measured << " rad/s against " << r.expected;
    EXPECT_LT(r.tilt_at_landing, 1e-3) << theta0;
  }
}

// The leapfrog steps of error-controlled length (sim.contact_tol, a polyhedron in `impulse`):
// drift-kick-drift, ceiling 3 ms, the held corners' bias from their acceleration in the free
// rotation (stepper_trial.cpp, leapfrog_bias). Measured 2026-11-29 (lead; relative errors, the
// table below prints them):
//   tol     sliding block  rocking 0.02 rad  0.1 rad    0.3 rad
//   1e-3    +0.0015 %      +0.044 %          +0.040 %   +0.074 %
//   3e-4    +0.0015 %      +0.016 %          +0.072 %   -0.0084 %
//   1e-4    +0.0015 %      -0.0038 %         +0.034 %   -0.0066 %
//   3e-5    +0.0015 %      -0.011 %          +0.0010 %  +0.0049 %
//   1e-5    +0.0015 %      +0.0010 %         +0.0008 %  +0.0009 %
//   1e-6    +0.0015 %      -0.0022 %         -0.0019 %  +0.0012 %
// Fixed 3 ms steps: +0.0015 % (-0.88 % before the mean-velocity path) and -2.7 %. Before the bias held the
// pivot's whole acceleration (normal part only, or none) the rocking die read 0.5-1.5 % low at
// some tolerances: its pivot left the floor every few steps and landed again plastically.
TEST(SustainedChecks, LeapfrogTable) {
  std::printf("leapfrog (drift-kick-drift, ceiling 3 ms): relative errors\n  tol     sliding      rock 0.02    rock 0.1     rock 0.3\n");
  for (double tol : {1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 1e-6}) {
    std::printf("  %.0e  %+.3e   %+.3e   %+.3e   %+.3e\n", tol, sliding_block(adaptive_steps(tol)).rel_error,
                rocking_die(adaptive_steps(tol), 0.02).rel_error, rocking_die(adaptive_steps(tol), 0.1).rel_error,
                rocking_die(adaptive_steps(tol), 0.3).rel_error);
  }
}
TEST(SustainedChecks, LeapfrogSlidingBlockStopsAtTheCoulombDistance) {
  const CheckResult r = sliding_block(adaptive_steps(1e-4));
  EXPECT_LT(std::abs(r.rel_error), 1e-4) << r.measured << " m against " << r.expected;
}
TEST(SustainedChecks, LeapfrogRockingDieLandsWithTheSpeedEnergyGives) {
  for (double theta0 : {0.02, 0.1, 0.3}) {
    const RockingResult r = rocking_die(adaptive_steps(1e-4), theta0);
    EXPECT_LT(std::abs(r.rel_error), 0.0025) << theta0 << " rad: " << r.measured << " rad/s against " << r.expected;
    EXPECT_LT(r.tilt_at_landing, 1e-3) << theta0;
  }
}
TEST(SustainedChecks, LeapfrogRockingDieAtEveryTolerance) {
  for (double tol : {1e-3, 3e-4, 1e-4, 3e-5, 1e-5}) {
    for (double theta0 : {0.02, 0.1, 0.3}) {
      const RockingResult r = rocking_die(adaptive_steps(tol), theta0);
      EXPECT_LT(std::abs(r.rel_error), 0.0025) << tol << " " << theta0 << " rad: " << r.rel_error;
    }
  }
}
TEST(SustainedChecks, LeapfrogConvergesWithItsTolerance) {
  const double loose = rocking_die(adaptive_steps(1e-3), 0.1).rel_error;
  const double tight = rocking_die(adaptive_steps(1e-6), 0.1).rel_error;
  EXPECT_LT(std::abs(tight), 0.1 * std::abs(loose)) << loose << " at 1e-3, " << tight << " at 1e-6";
}

// The quarter upright on its band (sustained_checks.hpp, e and f), the motions a dropped quarter's
// edge outcomes come from. The barrier is ~19 um of lift and a coin stays upright for seconds, so
// a step that takes even ~1 um/s from an upright coin's wobble moves the edge rate. Measured
// 2026-11-29 (lead), drift-kick-drift rim steps: the wobbling roller (30 rad/s, 2 rad/s of tilt
// rate, no resistances) loses at most 0.02 um/s on one rim circle at every step from 1 to 0.025
// ms, and 6.89-6.95 um/s at the rim changes (the other circle landing: plastic); its wobble decays
// from 3.1 to 2.75 deg in 1 s at every step. The spinning coin (30 rad/s, 1 deg) falls at 11.0 /
// 11.8 / 12.4 / 12.4 / 12.3 / 12.6 rad/s at 1 / 0.5 / 0.2 / 0.1 / 0.05 / 0.025 ms (at 5.5-6.1 s;
// how long the tilt takes to grow varies by ~0.1 s at the finest steps). The first-order steps
// lost 21.7 / 5.6 / 0.7 um/s on one rim at 1 / 0.2 / 0.025 ms, and at 1 ms held the spinning coin
// upright until it was captured `edge` at 2.9 rad/s.
TEST(SustainedChecks, UprightQuarterTable) {
  const std::vector<double> steps = {1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2.5e-5};
  std::printf("the quarter upright on its band, FixedStepper as `impulse` runs it\n"
              "  step (ms) | wobbling roller: dE/dt (um/s of lift) one rim  both rims  neither | tilt amp. start, end (deg)"
              " | spinning coin: end, spin (rad/s), t (s)\n");
  std::vector<RollerResult> roll;
  std::vector<SpinResult> spin;
  for (double h : steps) {
    roll.push_back(wobbling_roller(fixed_steps(h)));
    spin.push_back(spinning_upright(fixed_steps(h)));
    const RollerResult& r = roll.back();
    const SpinResult& p = spin.back();
    std::printf("  %8.3f  |  %+9.2f  %+9.2f  %+9.2f | %5.2f %5.2f | %-8s %6.2f %6.2f\n", h * 1e3, r.one_rim * 1e6,
                r.two_rims * 1e6, r.none * 1e6, r.amp_start * 180.0 / kPi, r.amp_end * 180.0 / kPi,
                p.captured ? "captured" : "fell", p.spin, p.t);
  }
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const RollerResult& r = roll[i];
    EXPECT_LT(r.one_rim + r.two_rims + r.none, 1e-9);  // never a gain
    // The steps take nothing from a coin on one rim circle (0.1 um/s: 1/200 of 1 ms's first-order
    // loss), and the rim changes' loss is the finest step's at every step.
    EXPECT_LT(std::abs(r.one_rim), 1e-7) << steps[i];
    EXPECT_NEAR(r.two_rims, roll.back().two_rims, 0.05 * std::abs(roll.back().two_rims)) << steps[i];
    EXPECT_FALSE(spin[i].captured) << steps[i];  // the spinning coin falls at every step
  }
  // The spin at 4 s, while every run still spins upright, converges at second order: 1 / 0.2 /
  // 0.05 / 0.025 ms read 16.618 / 17.002 / 17.056 / 17.062 rad/s (lead, 2026-11-29). Second order
  // from 0.2 ms's -0.35 % puts 0.05 ms within ~0.03 % of the limit: 0.1 % allowed between the two
  // finest. (Not the spin at the fall: when the tilt grows enough to fall varies by ~0.1 s between
  // the finest steps, 5.52 against 5.62 s, as the spin decays at ~3.3 rad/s^2: 2-3 %, so that is
  // held to 3 % only.)
  EXPECT_NEAR(spin[steps.size() - 2].spin, spin.back().spin, 0.03 * spin.back().spin);
  for (std::size_t i = 0; i < steps.size(); ++i) std::printf("  spin at 4 s, %.3f ms: %.5f rad/s\n", steps[i] * 1e3, spin[i].spin_4s);
  EXPECT_NEAR(spin[steps.size() - 2].spin_4s, spin.back().spin_4s, 1e-3 * spin.back().spin_4s);
}

// At the default step (0.2 ms) the spinning coin falls (at 1 ms the first-order step's damping of
// its tilt held it upright until it was captured `edge`), and spins at 4 s as the finest steps give
// within 0.5 % (today -0.35 %; the fall's spin within 3 %, today +0.2 %: UprightQuarterTable on why
// the fall's is looser).
TEST(SustainedChecks, SpinningCoinFallsAtTheDefaultStep) {
  const SpinResult ref = spinning_upright(fixed_steps(5e-5));
  const SpinResult r = spinning_upright(fixed_steps(kDefault));
  EXPECT_FALSE(r.captured) << "held upright until captured at " << r.spin << " rad/s";
  EXPECT_NEAR(r.spin_4s, ref.spin_4s, 5e-3 * ref.spin_4s) << "at 4 s " << r.spin_4s << " rad/s, at 0.05 ms " << ref.spin_4s;
  EXPECT_NEAR(r.spin, ref.spin, 0.03 * ref.spin) << "fell at " << r.spin << " rad/s, at 0.05 ms " << ref.spin;
}

// The steps' loss from a wobbling roller at the default step: at most a fifth of the barrier over
// the ~5 s a captured dropped quarter spends upright (0.2 * 19 um / 5 s ~ 0.76 um/s). Today 0.00
// um/s (drift-kick-drift rim steps); the first-order ones lost 5.6 um/s at 0.2 ms.
TEST(SustainedChecks, WobblingRollerAtTheDefaultStep) {
  const DieModel m = upright_quarter_model(false);
  const double barrier = m.face_escape[2] - m.face_height[2];
  const RollerResult r = wobbling_roller(fixed_steps(kDefault));
  EXPECT_LT(std::abs(r.one_rim), 0.2 * barrier / 5.0) << r.one_rim * 1e6 << " um/s";
}

// The rocking coin (sustained_checks.hpp, g): the lift it loses in 0.8 s, rocking between its rim
// circles from 1 and 3 deg, is the finest step's within 2 % at every step. Measured 2026-11-29
// (lead), drift-kick-drift rim steps, 1 / 0.2 / 0.05 / 0.0125 ms: from 1 deg 1.113 / 1.111 / 1.108 /
// 1.106 um, from 3 deg 0.737 / 0.733 / 0.734 / 0.735 um. The first-order steps lost 9.46 / 2.60 /
// 1.47 / 1.19 um from 1 deg: each of the rim circle's landings, plastic in both, also lost the
// steps' own first-order share.
TEST(SustainedChecks, RockingCoinLosesTheSameAtEveryStep) {
  for (double tilt_deg : {1.0, 3.0}) {
    const double tilt = tilt_deg * kPi / 180.0;
    const double ref = rocking_coin(fixed_steps(1.25e-5), tilt);
    EXPECT_GT(ref, 0.5e-6) << tilt_deg;  // it does lose: the landings are plastic
    for (double h : {1e-3, 2e-4, 5e-5}) {
      const double lost = rocking_coin(fixed_steps(h), tilt);
      std::printf("rocking coin from %.0f deg, %.4f ms: %.3f um of lift lost in 0.8 s (finest %.3f)\n", tilt_deg,
                  h * 1e3, lost * 1e6, ref * 1e6);
      EXPECT_NEAR(lost, ref, 0.02 * ref) << tilt_deg << " deg, " << h * 1e3 << " ms";
    }
  }
}

// A spinning die whose face lies a little tilted and below the floor (a landing leaves it so) must
// come to lie flat, within rest.cpp's 1e-6 r, so that the "lying flat" rule can end the toss: its
// spin keeps the energy above every basin's barrier, so nothing else will. The leapfrog asks each
// held corner for its own rise (leapfrog_bias); with one rise for all corners the face stayed
// tilted by its landing's 2 um for as long as it spun (no step flattened it: this test failed).
TEST(SustainedChecks, LeapfrogFlattensATiltedSpinningFace) {
  SceneDef def = fair_scene();
  def.materials["plastic"].friction = 0.0;  // the spin lasts
  const DieModel m = compile(def);
  RigidState s;
  const double tilt = 2e-6 / 0.03;  // 2 um across the 3 cm face
  s.R = Eigen::AngleAxisd(tilt, Vec3(1.0, 0.3, 0.0).normalized()).toRotationMatrix() * m.geo_to_body.transpose();
  s.position = Vec3(0.0, 0.0, -lowest_offset(m, s.R) - 3e-6);  // the deepest corner 3 um down
  s.omega = Vec3(0.0, 0.0, 40.0);  // above the barrier: 1/2 I w^2 > m g (6.2 mm)
  ASSERT_LT(rest_face_down(m, s, 0.5), 0);
  SustainedStep step = adaptive_steps(1e-3)(m);
  int flat_after = -1;
  for (int k = 0; k < 40 && flat_after < 0; ++k) {
    step(s);
    if (rest_face_down(m, s, 0.5) == 5) flat_after = k + 1;
  }
  EXPECT_GT(flat_after, 0) << "still tilted after 40 steps";
  EXPECT_LE(flat_after, 10);
}

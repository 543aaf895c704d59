// One toss, top to bottom: draw the throw, fly, strike, repeat, read the face.
#pragma once

#include <chrono>
#include <cstdint>
#include <vector>

#include "sim/body/die_model.hpp"
#include "sim/dynamics/corrections.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/models/initial_state.hpp"

namespace dicesim {

class StepObserver;  // sim/dynamics/contact_stepper.hpp

enum class TossStatus : std::uint8_t {
  Settled = 0,     // ended by the fidelity's rule; face is the answer
  Unresolved = 1,  // hit the bounce or time cap, or chattered (Zeno): no answer, counted
  Invalid = 2,     // the drawn initial state is impossible (die below the floor, non-finite)
};
const char* to_string(TossStatus s);

struct TossResult {
  int face = 0;        // face label (settled tosses), else 0
  int face_index = -1; // the face read, in the model's face order (a box: +x, -x, +y, -y, +z, -z), else -1
  int outcome = -1;    // index of `face` in the model's outcome_labels (label order), else -1
  TossStatus status = TossStatus::Invalid;
  int bounces = 0;
  double t_end = 0.0;  // simulated time at the end (s)
  Corrections corrections;  // guards and fallbacks that fired during the toss (should all be 0)
};

// Records face index f as the result read (label and outcome from the model).
inline void set_result_face(const DieModel& m, int f, TossResult& r) {
  r.face_index = f;
  r.face = m.face_labels[static_cast<std::size_t>(f)];
  r.outcome = m.face_outcome[static_cast<std::size_t>(f)];
}

// One impact, for traces and replays.
struct BounceRecord {
  int bounce = 0;      // 1-based
  double t = 0.0;      // since release (s)
  RigidState before;   // at the instant of contact
  RigidState after;    // right after the impulse
  int vertex = -1;
  double impulse = 0.0;
};

// Where a toss's time goes, for `dicesim bench` (TossProbe::timing). Every model times the phases
// it has: drawing the throw; the exact flight and its contact search (with the contact set);
// impacts (the impulse law and, for `paper`, the stop rule); fixed steps of sustained contact
// (`impulse`) or of the whole toss (`stepped`); rest checks.
enum class Phase : std::uint8_t { Draw, Search, Impact, Steps, Rest };
inline constexpr int kPhaseCount = 5;
const char* to_string(Phase p);

// Optional instruments for one or many tosses (null in the hot path: nothing is recorded).
struct TossProbe {
  std::vector<BounceRecord>* trace = nullptr;  // every impact appended
  bool timing = false;                         // time the phases below (two clock reads per phase entered)
  double phase_s[kPhaseCount] = {};            // seconds in each Phase
  std::uint64_t phase_n[kPhaseCount] = {};     // times each Phase was entered
  std::uint64_t search_iterations = 0;         // conservative-advancement steps
  std::uint64_t flights = 0;
  // `impulse` and `stepped`: Gauss-Seidel sweeps of every contact solve, fixed steps taken, and
  // the largest relative energy gain of any impact (kinetic) or fixed step (kinetic + m g z):
  // the impact law and the stepper promise it is 0 up to rounding.
  std::uint64_t pgs_sweeps = 0;
  std::uint64_t steps = 0;
  std::uint64_t located_steps = 0;  // fixed steps shortened to the instant a new corner touches
  std::uint64_t located_trials = 0;  // their trial steps (each a whole step of shortened length)
  std::uint64_t located_capped = 0;  // ... not within the touch tolerance in the trials allowed (the longest above taken)
  std::uint64_t nudges = 0;          // exact balances at rest broken by the toss's tiebreak (a spin of 1e-4 sqrt(g/r))
  double max_energy_gain = 0.0;
  double max_step_rise = 0.0;    // plain kinetic + m g z over one fixed step: its largest rise / (m g) (m)
  double max_rise_excess = 0.0;  // ... its largest relative excess over m g (the deepest held corner's start depth)
  double max_penetration = 0.0;  // curved dice: deepest rim below the floor at any fixed step's end (m)
  std::uint64_t halved = 0;            // curved dice: fixed steps halved (a capped support)
  std::uint64_t curvature_capped = 0;  // curved dice: supports at a step's middle capped to gain no energy (any trial)
  std::uint64_t support_search_capped = 0;  // curved dice: support searches out of iterations (end above the floor taken; any trial)
  std::uint64_t slaps = 0;             // curved dice: fixed steps shortened to a slapping face's arrival
  std::uint64_t slap_no_arrival = 0;   // curved dice: slaps whose far half did not arrive (the plain step taken)
  std::uint64_t slap_rim_below = 0;    // curved dice: located slaps that left the rim below (the plain search again)
  std::uint64_t flat_landed = 0;       // curved dice: steps taken again with a nearly flat face's tripod struck
  std::uint64_t face_jumped = 0;       // ... of them because the lowest point jumped across the face (kind B)
  std::uint64_t face_jump_declined = 0;  // kind B steps taken again with the face struck but not kept
  std::uint64_t rim_struck = 0;          // a flat coin's tripod impact taken again with its rim's approaching arc struck
  std::uint64_t rim_strike_declined = 0;  // ... taken again but not kept
  std::uint64_t dual_solves = 0;       // impacts whose restitution friction the dual solve took (Gauss-Seidel stalled)
  std::uint64_t exact_fallbacks = 0;   // solves an exact second method took (ImpactResult::exact_fallbacks)
  double max_held_sink = 0.0;          // flat dice: deepest held corner below the floor at any fixed step's end (m)
  std::uint64_t held_sinks = 0;        // flat dice: fixed steps whose held corners sank more than the bound
  std::uint64_t sink_shortened = 0;    // flat dice, `impulse`: fixed steps tried again shorter for that bound
  std::uint64_t short_steps = 0;       // flat dice, `impulse`: fixed steps whose full length was below contact_step
  std::uint64_t rise_dropped = 0;      // flat dice, `impulse`: fixed steps whose held corners' rise would gain energy
  // World tosses (several dice, obstacles; world_toss.cpp): windows of conservative advancement,
  // contacts struck between two bodies (die and die, die and obstacle), dice struck at rest and
  // moving again, narrow-phase calls that ended at their iteration cap (their best estimate taken).
  std::uint64_t windows = 0;
  std::uint64_t windows_halved = 0;  // ... taken again shorter (a nearly touching pair went too deep)
  std::uint64_t interactions = 0;
  std::uint64_t woken = 0;
  std::uint64_t sweeps_capped = 0;  // instants whose strikes reached their cap, slow contacts left touching
                                    // (also counted: Corrections::pgs_unconverged)
  std::uint64_t held_at_rest = 0;  // slow die-on-die strikes against a die at rest, that die held where it lies
  std::uint64_t patch_witness_only = 0;  // touches whose contact patch came out empty: struck at the witness point alone
                                         // (also counted: Corrections::fallbacks)
  std::uint64_t perched = 0;  // dice found held still off their rest by fixed bodies (world_toss.cpp: perched)
  std::uint64_t retries_capped = 0;  // risky windows still too deep after kMaxRetries retries, taken as they were
                                     // (their overlap, lifted out next, is Corrections::contact_overlaps)
  std::uint64_t narrow_degenerate = 0;
  std::uint64_t witness_strikes = 0;  // die-on-obstacle strikes whose nearest point, still approaching after its corners', was struck too
  double max_overlap = 0.0;  // the deepest overlap of two bodies found after a window (m), lifted out
                             // (beyond 1e-4 r also counted: Corrections::contact_overlaps)
  RigidState* final_state = nullptr;           // impulse, stepped: the state when the toss ended
  StepObserver* steps_observer = nullptr;      // impulse, stepped: every state of the fixed steps (contact_stepper.hpp)
};

// Times one phase of a toss into probe->phase_s while in scope; reads no clock (and costs one
// test of a pointer that is null in the hot path) unless probe->timing.
class PhaseTimer {
 public:
  PhaseTimer(TossProbe* probe, Phase phase) : probe_(probe && probe->timing ? probe : nullptr), phase_(phase) {
    if (probe_) t0_ = std::chrono::steady_clock::now();
  }
  ~PhaseTimer() { stop(); }
  // Ends the phase before the scope does (once).
  void stop() {
    if (!probe_) return;
    const auto k = static_cast<std::size_t>(phase_);
    probe_->phase_s[k] += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    ++probe_->phase_n[k];
    probe_ = nullptr;
  }
  PhaseTimer(const PhaseTimer&) = delete;
  PhaseTimer& operator=(const PhaseTimer&) = delete;

 private:
  TossProbe* probe_;
  Phase phase_;
  std::chrono::steady_clock::time_point t0_;
};

// Chatter guard (`paper`): this many impacts in a row, each less than kZenoInterval after the
// previous one, mean the die is pivoting on a corner and will never satisfy the stop rule.
inline constexpr double kZenoInterval = 1e-7;  // s
inline constexpr int kZenoRun = 8;

// Toss number `index` of a run with `seed`.
TossResult toss(const DieModel& m, std::uint64_t seed, std::uint64_t index, TossProbe* probe = nullptr);

// The same from a given initial state (tests, replays of special cases).
TossResult toss_from(const DieModel& m, const InitialState& init, TossProbe* probe = nullptr);

// The initial state in the model's body frame (COM at init.com_position).
RigidState to_body_state(const DieModel& m, const InitialState& init);

}  // namespace dicesim

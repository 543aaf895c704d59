// Fixed-step time integration of the die with the floor: gravity, torque-free rotation (world
// angular momentum held between impulses), and at every step the corners touching the floor
// solved together with Coulomb friction (sim/friction_impact.hpp): with restitution when a corner
// arrives faster than the impact threshold (an impact), perfectly plastic otherwise (sustained
// contact: resting, sliding, rolling, tipping). Semi-implicit Euler, first order: the answer
// converges as h -> 0. The whole of the `stepped` fidelity, and `impulse`'s sustained-contact phases.
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/dynamics/flight.hpp"

namespace dicesim {

// Which approach speed makes a step's contact an impact (restitution, counted against
// sim.max_bounces) rather than sustained contact (plastic, not counted).
//  Gravity: 4 g h, what gravity alone adds in a step (`impulse`'s sustained contact, unchanged).
//  Contact: h (4 g + (1 + mu_max) g m r^2 / I_min + 4 |w|^2 r), r the bounding radius: a bound on
//   a corner's approach built up in one step of sustained contact, from gravity, from the angular
//   acceleration that contact forces of order m g (normal plus friction) give at lever r, and
//   from the spin's centripetal term. Under the gravity threshold a die sliding flat on a face
//   rocks from corner to corner (friction pitches it; one corner touches per step), its corners
//   arriving at ~6-8 g h, and a fast-spinning contact corner drifts in by ~w^2 r h per step:
//   every step was a counted, bouncing impact, so the count grew like 1/h and fine steps hit
//   sim.max_bounces. Both thresholds vanish with h (a genuine impact arrives at a speed that
//   does not), so the limit h -> 0 is the same physics.
enum class ImpactThreshold { Gravity, Contact };

class FixedStepper {
 public:
  FixedStepper(const DieModel& m, double h, ImpactThreshold threshold = ImpactThreshold::Gravity);

  // Advances s by one step h. Returns the number of corners that were in contact.
  int step(RigidState& s);

  double h() const { return h_; }
  int impacts = 0;          // steps whose contact solve had restitution
  int energy_clamps = 0;    // impacts the energy guard scaled back

 private:
  const DieModel* m_;
  double h_, v_impact_, touch_tol_;
  double v_spin_ = 0.0;  // Contact: 4 h r, the factor of |w|^2 in the threshold
};

enum class StepperExit { Settled, LiftOff, Unresolved };

struct StepperOutcome {
  StepperExit exit = StepperExit::Unresolved;
  int face_down = -1;  // Settled: face index on the floor
  int nudges = 0;      // exact balances broken by the toss's tiebreak
};

// Steps from (s, t) until the die must come to rest (sim/rest.hpp), the time cap, the impact cap
// (`impacts` counts on), or, with allow_liftoff, until no corner touches or will touch within two
// steps (the caller's exact flight takes over). A die at rest in an exact unstable balance (on an
// edge or corner) gets an infinitesimal spin whose direction comes from `tiebreak`.
StepperOutcome run_fixed_steps(const DieModel& m, RigidState& s, double& t, int& impacts, double h, double tiebreak,
                               bool allow_liftoff, ImpactThreshold threshold = ImpactThreshold::Gravity);

}  // namespace dicesim

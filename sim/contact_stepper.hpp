// Fixed-step time integration of the die with the floor: gravity, torque-free rotation (world
// angular momentum held between impulses), and at every step the corners touching the floor
// solved together with Coulomb friction (sim/friction_impact.hpp): with restitution when a corner
// arrives faster than 4 g h (an impact), perfectly plastic otherwise (sustained contact: resting,
// sliding, rolling, tipping). Semi-implicit Euler, first order: the answer converges as h -> 0.
// The whole of the `stepped` fidelity, and `impulse`'s sustained-contact phases.
#pragma once

#include "sim/die_model.hpp"
#include "sim/flight.hpp"

namespace dicesim {

class FixedStepper {
 public:
  FixedStepper(const DieModel& m, double h);

  // Advances s by one step h. Returns the number of corners that were in contact.
  int step(RigidState& s);

  double h() const { return h_; }
  int impacts = 0;          // steps whose contact solve had restitution
  int energy_clamps = 0;    // impacts the energy guard scaled back

 private:
  const DieModel* m_;
  double h_, v_impact_, touch_tol_;
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
                               bool allow_liftoff);

}  // namespace dicesim

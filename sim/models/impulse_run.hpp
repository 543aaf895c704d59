// `impulse`'s toss as a resumable run: one die's exact flights, floor impacts and sustained
// contact, advanced to a given time and picked up again there. run_impulse advances it to the end
// in one call; a world toss (world_toss.cpp) advances every die window by window and strikes the
// dice against each other and the obstacles in between.
#pragma once

#include <limits>

#include "sim/body/die_model.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/models/toss.hpp"

namespace dicesim {

enum class RunState : std::uint8_t { Running, Settled, Unresolved };

struct ImpulseRun {
  const DieModel* m = nullptr;
  RigidState s;
  double t = 0.0;
  double tiebreak = 0.0;
  int bounces = 0;
  bool sustained = false;     // in the stepper's hands (sustained contact with the floor)
  bool after_impact = false;  // s is the state right after a floor impact: sustained contact possible
  double since_impact = 0.0;  // time from that impact to the current flight's start (a window cut the flight)
  RunState state = RunState::Running;
  int face_down = -1;         // Settled: the face on the floor
  StepperStats stats;
  Corrections corrections;    // the impacts' own (the stepper's are in stats)

  ImpulseRun(const DieModel& model, const RigidState& start, double tie) : m(&model), s(start), tiebreak(tie) {}

  // Advances until t_stop (exactly: a flight is evaluated there, a sustained phase's last step is
  // shortened to end there), rest or a cap.
  void advance(double t_stop, TossProbe* probe);

  // The TossResult of a run that has ended, its statistics added to the probe.
  TossResult result(TossProbe* probe);
};

inline constexpr double kRunForever = std::numeric_limits<double>::infinity();

}  // namespace dicesim

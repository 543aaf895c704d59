// `impulse`'s toss as a resumable run: one die's exact flights, floor impacts and sustained
// contact, advanced to a given time and picked up again there. run_impulse advances it to the end
// in one call; a world toss (world_toss.cpp) advances every die window by window and strikes the
// dice against each other and the obstacles in between.
#pragma once

#include <limits>
#include <optional>

#include "sim/body/die_model.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/models/toss.hpp"

namespace dicesim {

enum class RunState : std::uint8_t { Running, Settled, Unresolved };

// A flight in progress: where it started and its next floor contact, searched once for the whole
// flight (a window that ends in flight evaluates the same flight there and picks it up again).
struct FlightAhead {
  Flight path;
  double t0 = 0.0;         // the toss time at its start
  ContactSearch contact;   // times relative to t0
};

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
  std::optional<FlightAhead> flight;  // set while flying (not sustained, not at rest)
  StepperStats stats;
  Corrections corrections;    // the impacts' own (the stepper's are in stats)

  ImpulseRun(const DieModel& model, const RigidState& start, double tie) : m(&model), s(start), tiebreak(tie) {}

  // Advances until t_stop (exactly: a flight is evaluated there, a sustained phase's last step is
  // shortened to end there), rest or a cap.
  void advance(double t_stop, TossProbe* probe);

  // The rest check every flight's start makes: true (and settled) if the die rests here.
  bool settles_now(TossProbe* probe);
  // Starts the flight from s at t, its contact searched to max_time (untimed: the caller's phase).
  void start_flight(TossProbe* probe);

  // s was changed from outside (a world toss's strike): the flight in progress, if any, is gone.
  void moved() { flight.reset(); }

  // The TossResult of a run that has ended, its statistics added to the probe.
  TossResult result(TossProbe* probe);
};

inline constexpr double kRunForever = std::numeric_limits<double>::infinity();

}  // namespace dicesim

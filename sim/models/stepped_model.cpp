// `stepped`: fixed-step integration of flight, impacts, sliding, rolling and tipping until rest.
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/models/fidelity_models.hpp"
#include "sim/dynamics/rest.hpp"

namespace dicesim {

TossResult run_stepped(const DieModel& m, RigidState s, double tiebreak, TossProbe* probe) {
  TossResult r;
  double t = 0.0;
  int impacts = 0;
  StepperStats stats;
  if (probe) stats.observer = probe->steps_observer;
  PhaseTimer timer(probe, Phase::Steps);
  const StepperOutcome o = run_fixed_steps(m, s, t, impacts, m.step, tiebreak, /*allow_liftoff=*/false,
                                           ImpactThreshold::Contact, &stats);
  timer.stop();
  if (probe) {
    probe->flights += 1;
    add_stepper_stats(*probe, stats);
  }
  if (probe && probe->final_state) *probe->final_state = s;
  r.corrections = stats.corrections;
  r.bounces = impacts;
  r.t_end = t;
  if (o.exit != StepperExit::Settled) {
    r.status = TossStatus::Unresolved;
    return r;
  }
  r.status = TossStatus::Settled;
  set_result_face(m, result_face(m, o.face_down), r);
  return r;
}

}  // namespace dicesim

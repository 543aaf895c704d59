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
  PhaseTimer timer(probe, Phase::Steps);
  const StepperOutcome o = run_fixed_steps(m, s, t, impacts, m.step, tiebreak, /*allow_liftoff=*/false,
                                           ImpactThreshold::Contact, &stats);
  timer.stop();
  if (probe) {
    probe->flights += 1;
    probe->pgs_sweeps += stats.sweeps;
    probe->steps += stats.steps;
    probe->located_steps += stats.located;
    probe->located_trials += stats.located_trials;
    probe->max_energy_gain = std::max(probe->max_energy_gain, stats.max_energy_gain);
    probe->max_penetration = std::max(probe->max_penetration, stats.max_penetration);
    probe->halved += stats.halved;
    probe->max_held_sink = std::max(probe->max_held_sink, stats.max_held_sink);
    probe->held_sinks += stats.held_sinks;
    probe->sink_shortened += stats.sink_shortened;
    probe->short_steps += stats.short_steps;
    probe->rise_dropped += stats.rise_dropped;
    probe->curvature_capped += stats.curvature_capped;
    probe->slaps += stats.slaps;
    probe->slap_no_arrival += stats.slap_no_arrival;
    probe->slap_rim_below += stats.slap_rim_below;
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

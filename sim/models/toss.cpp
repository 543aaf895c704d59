#include "sim/models/toss.hpp"

#include <cmath>

#include <cstring>

#include <Random123/philox.h>

#include "sim/dynamics/contact.hpp"
#include "sim/body/world.hpp"
#include "sim/models/fidelity_models.hpp"
#include "sim/models/world_toss.hpp"
#include "sim/body/outcome.hpp"

namespace dicesim {

const char* to_string(TossStatus s) {
  switch (s) {
    case TossStatus::Settled: return "settled";
    case TossStatus::Unresolved: return "unresolved";
    case TossStatus::Invalid: return "invalid";
  }
  return "?";
}

const char* to_string(Phase p) {
  switch (p) {
    case Phase::Draw: return "draw";
    case Phase::Search: return "search";
    case Phase::Impact: return "impacts";
    case Phase::Steps: return "steps";
    case Phase::Rest: return "rest";
  }
  return "?";
}

RigidState to_body_state(const DieModel& m, const InitialState& init) {
  RigidState s;
  s.position = init.com_position;
  s.velocity = init.velocity;
  s.R = init.orientation * m.geo_to_body.transpose();
  s.omega = init.omega;
  return s;
}

namespace {

bool starts_valid(const DieModel& m, const RigidState& s) {
  if (!s.position.allFinite() || !s.velocity.allFinite() || !s.omega.allFinite() || !s.R.allFinite()) return false;
  if (m.catch_end) return true;  // caught in the hand: the floor plays no part
  const double tol = 1e-9 * m.bounding_radius;
  if (m.curved()) return s.position.z() + rim_lowest(m, s.R) >= -tol;
  for (const Vec3& v : m.vertices)
    if (s.position.z() + s.R.row(2).dot(v) - m.rounding < -tol) return false;
  return true;
}

// Re-orthonormalise between flights so that rounding cannot accumulate over many bounces.
Mat3 orthonormal(const Mat3& R) { return Quat(R).normalized().toRotationMatrix(); }

TossResult run_paper(const DieModel& m, RigidState s, TossProbe* probe) {
  TossResult r;
  double t_now = 0.0;
  double last_impact = -1.0;
  int zeno_run = 0;
  for (;;) {
    ContactSearch c;
    {
      const PhaseTimer timer(probe, Phase::Search);
      const Flight flight(m, s);
      c = flight.next_contact(m.max_time - t_now);
    }
    if (probe) {
      probe->search_iterations += static_cast<std::uint64_t>(c.iterations);
      ++probe->flights;
    }
    if (c.outcome != ContactSearch::Outcome::Contact) {
      r.status = TossStatus::Unresolved;
      r.t_end = t_now + c.t;
      return r;
    }
    const PhaseTimer timer(probe, Phase::Impact);
    t_now += c.t;
    RigidState before = c.at;  // = flight.state(c.t)
    before.R = orthonormal(before.R);
    s = before;
    const Impact imp = apply_vertex_impact(m, s, c.vertex);
    ++r.bounces;
    if (probe && probe->trace) probe->trace->push_back({r.bounces, t_now, before, s, c.vertex, imp.impulse});

    // The seed's rule: the toss is over when the COM's rebound speed is below the threshold.
    if (s.velocity.z() < m.stop_speed) {
      r.status = TossStatus::Settled;
      set_result_face(m, read_face_index(m, s.R), r);
      r.t_end = t_now;
      return r;
    }
    zeno_run = (last_impact >= 0.0 && t_now - last_impact < kZenoInterval) ? zeno_run + 1 : 0;
    last_impact = t_now;
    if (zeno_run >= kZenoRun || r.bounces >= m.max_bounces) {
      r.status = TossStatus::Unresolved;
      r.t_end = t_now;
      return r;
    }
  }
}

// The toss's tiebreak for exact balances, in [0, 1): Philox keyed by the seed, on a counter word
// the throw's own draws never use, so the throw is unchanged.
double tiebreak_of(std::uint64_t seed, std::uint64_t index) {
  r123::Philox4x32 gen;
  const r123::Philox4x32::key_type key = {{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32)}};
  const r123::Philox4x32::ctr_type ctr = {{static_cast<std::uint32_t>(index), static_cast<std::uint32_t>(index >> 32), 0u, 0xD1CEu}};
  const auto out = gen(ctr, key);
  return static_cast<double>((static_cast<std::uint64_t>(out.v[0]) << 21) ^ out.v[1]) * 0x1.0p-53;
}

// Without a toss index (replays, tests): a hash of the initial state, so still deterministic.
double tiebreak_of(const InitialState& init) {
  std::uint64_t h = 0x9E3779B97F4A7C15ull;
  const double parts[] = {init.com_position.z(), init.velocity.x(), init.velocity.y(), init.velocity.z(),
                          init.omega.x(), init.omega.y(), init.omega.z(), init.orientation(0, 0), init.orientation(1, 2)};
  for (double d : parts) {
    std::uint64_t b;
    std::memcpy(&b, &d, sizeof b);
    h = (h ^ b) * 0x100000001B3ull;
    h ^= h >> 29;
  }
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

// sim.end = "catch": exact torque-free flight to the catch time, then the face most nearly up
// (never the side). The COM's path does not matter: the hand is wherever the die is.
TossResult run_catch(const DieModel& m, const RigidState& s, double t) {
  TossResult r;
  if (!(t > 0.0) || !std::isfinite(t)) return r;  // Invalid (a catch time <= 0: 1e-9 odds by the scene check)
  const TorqueFreeRotation rot(m.principal_moments, s.R, world_inertia(m, s.R) * s.omega);
  set_result_face(m, caught_face_index(m, rot.orientation(t)), r);
  r.status = TossStatus::Settled;
  r.t_end = t;
  return r;
}

TossResult caught_as_thrown(const DieModel& m, const RigidState& s) {
  TossResult r;
  set_result_face(m, caught_face_index(m, s.R), r);
  r.status = TossStatus::Settled;
  return r;
}

TossResult run(const DieModel& m, const InitialState& init, double tiebreak, TossProbe* probe) {
  const RigidState s = to_body_state(m, init);
  if (!starts_valid(m, s)) return TossResult{};  // status Invalid
  if (m.catch_end) {
    // `static` has no motion (its draw has no catch time): the face most nearly up as thrown.
    if (m.fidelity == Fidelity::Static) return caught_as_thrown(m, s);
    return run_catch(m, s, init.catch_time);
  }
  switch (m.fidelity) {
    case Fidelity::Paper: return run_paper(m, s, probe);
    case Fidelity::Static: {
      const PhaseTimer timer(probe, Phase::Rest);
      return run_static(m, s, tiebreak);
    }
    case Fidelity::Impulse: return run_impulse(m, s, tiebreak, probe);
    case Fidelity::Stepped: return run_stepped(m, s, tiebreak, probe);
    case Fidelity::Auto: break;  // resolved by compile(); never reaches a toss
  }
  return TossResult{};
}

// Die k's stream of a world toss: the first die's is the toss's own (seed, index), as alone.
std::uint64_t die_seed(std::uint64_t seed, int k) {
  return seed + static_cast<std::uint64_t>(k) * 0x9E3779B97F4A7C15ull;
}

// Several dice (sim/body/world.hpp): each die's throw from its own stream (hand = "shared": the
// first die's release position and velocity for all), plus its offset; `static` reads each die
// alone (no contact between them), `impulse` runs the world.
TossResult toss_world(const DieModel& m, std::uint64_t seed, std::uint64_t index, TossProbe* probe) {
  const World& w = *m.world;
  const bool motion = m.fidelity != Fidelity::Static;
  std::vector<RigidState> starts;
  std::vector<double> tiebreaks;
  InitialState first;
  {
    const PhaseTimer timer(probe, Phase::Draw);
    for (int k = 0; k < w.size(); ++k) {
      const DieModel& d = w.dice[static_cast<std::size_t>(k)];
      InitialState init = draw_initial_state(d.throw_, die_seed(seed, k), index, motion);
      if (k == 0) first = init;
      else if (w.hand == HandKind::Shared) {
        init.com_position = first.com_position;
        init.velocity = first.velocity;
      }
      init.com_position += w.offsets[static_cast<std::size_t>(k)];
      starts.push_back(to_body_state(d, init));
      tiebreaks.push_back(tiebreak_of(die_seed(seed, k), index));
      if (!starts_valid(d, starts.back())) return TossResult{};  // Invalid
    }
  }
  if (m.fidelity == Fidelity::Static) {
    const PhaseTimer timer(probe, Phase::Rest);
    int tuple = 0;
    for (int k = 0; k < w.size(); ++k) {
      const TossResult one = run_static(w.dice[static_cast<std::size_t>(k)], starts[static_cast<std::size_t>(k)],
                                        tiebreaks[static_cast<std::size_t>(k)]);
      if (one.status != TossStatus::Settled) return one;
      tuple += one.outcome * w.stride[static_cast<std::size_t>(k)];
    }
    TossResult r;
    r.status = TossStatus::Settled;
    r.outcome = w.tuple_outcome[static_cast<std::size_t>(tuple)];
    r.face = m.outcome_labels[static_cast<std::size_t>(r.outcome)];
    return r;
  }
  return run_world(m, starts, tiebreaks, probe);
}

}  // namespace

TossResult toss_from(const DieModel& m, const InitialState& init, TossProbe* probe) {
  if (m.world) return TossResult{};  // one initial state does not make a world's toss: Invalid
  return run(m, init, tiebreak_of(init), probe);
}

TossResult toss(const DieModel& m, std::uint64_t seed, std::uint64_t index, TossProbe* probe) {
  if (m.world) return toss_world(m, seed, index, probe);
  InitialState init;
  {
    const PhaseTimer timer(probe, Phase::Draw);
    // `static` reads only the orientation (and the height, for the start's validity).
    init = draw_initial_state(m.throw_, seed, index, /*motion=*/m.fidelity != Fidelity::Static);
  }
  // `paper` breaks no exact balances (its stop rule reads the face directly): no Philox block for it.
  const double tiebreak = m.fidelity == Fidelity::Paper ? 0.0 : tiebreak_of(seed, index);
  return run(m, init, tiebreak, probe);
}

}  // namespace dicesim

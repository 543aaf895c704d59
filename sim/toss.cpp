#include "sim/toss.hpp"

#include <chrono>
#include <cmath>

#include "sim/contact.hpp"
#include "sim/outcome.hpp"

namespace dicesim {

const char* to_string(TossStatus s) {
  switch (s) {
    case TossStatus::Settled: return "settled";
    case TossStatus::Unresolved: return "unresolved";
    case TossStatus::Invalid: return "invalid";
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
  const double tol = 1e-9 * m.bounding_radius;
  for (const Vec3& v : m.vertices)
    if (s.position.z() + s.R.row(2).dot(v) < -tol) return false;
  return true;
}

// Re-orthonormalise between flights so that rounding cannot accumulate over many bounces.
Mat3 orthonormal(const Mat3& R) { return Quat(R).normalized().toRotationMatrix(); }

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

TossResult run_paper(const DieModel& m, RigidState s, TossProbe* probe) {
  const bool timing = probe && probe->timing;
  Clock::time_point t0;
  TossResult r;
  double t_now = 0.0;
  double last_impact = -1.0;
  int zeno_run = 0;
  for (;;) {
    if (timing) t0 = Clock::now();
    const Flight flight(m, s);
    const ContactSearch c = flight.next_contact(m.max_time - t_now);
    if (probe) {
      probe->search_iterations += static_cast<std::uint64_t>(c.iterations);
      ++probe->flights;
      if (timing) probe->flight_s += seconds_since(t0);
    }
    if (c.outcome != ContactSearch::Outcome::Contact) {
      r.status = TossStatus::Unresolved;
      r.t_end = t_now + c.t;
      return r;
    }
    if (timing) t0 = Clock::now();
    t_now += c.t;
    RigidState before = flight.state(c.t);
    before.R = orthonormal(before.R);
    s = before;
    const Impact imp = apply_vertex_impact(m, s, c.vertex);
    ++r.bounces;
    if (probe && probe->trace) probe->trace->push_back({r.bounces, t_now, before, s, c.vertex, imp.impulse});
    if (timing) probe->impact_s += seconds_since(t0);

    // The seed's rule: the toss is over when the COM's rebound speed is below the threshold.
    if (s.velocity.z() < m.stop_speed) {
      r.status = TossStatus::Settled;
      r.face_index = top_face_index(m, s.R);
      r.face = m.face_labels[r.face_index];
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

}  // namespace

TossResult toss_from(const DieModel& m, const InitialState& init, TossProbe* probe) {
  const RigidState s = to_body_state(m, init);
  if (!starts_valid(m, s)) return TossResult{};  // status Invalid
  switch (m.fidelity) {
    case Fidelity::Paper: return run_paper(m, s, probe);
  }
  return TossResult{};
}

TossResult toss(const DieModel& m, std::uint64_t seed, std::uint64_t index, TossProbe* probe) {
  return toss_from(m, draw_initial_state(m.throw_, seed, index), probe);
}

}  // namespace dicesim

// FixedStepper's set-up and its step (contact_stepper.hpp): the step's decisions (impact, support,
// location of a new contact, a curved die's halvings, slaps and strikes) and its accounting. The
// stages it calls live in their own files (sim/dynamics/README.md).
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/contact_stepper_internal.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include "sim/body/rim.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/illinois.hpp"

namespace dicesim {

using stepper_detail::mechanical_energy;

FixedStepper::FixedStepper(const DieModel& m, double h, ImpactThreshold threshold, double max_sink,
                           const AdaptiveSteps& adaptive)
    : m_(&m),
      moments_(m.principal_moments),
      h_max_(h),
      adaptive_(adaptive),
      h_ctrl_(h),
      kick_g_(m.gravity),
      h_(h),
      v_impact_(sustained_contact_speed(m, adaptive.threshold_step > 0.0 ? adaptive.threshold_step : h)),
      touch_tol_(1e-7 * m.bounding_radius),
      max_sink_(m.curved() ? 0.0 : max_sink) {
  if (threshold == ImpactThreshold::Contact) {
    // Gravity keeps its safety factor 4; contact forces of order m g (normal plus friction) at
    // lever r add at most (1 + mu) g m r^2 / I_min per unit time; the spin adds |w|^2 r (factor 4).
    const double r = m.bounding_radius;
    const double lever = m.mass * r * r / m.principal_moments.minCoeff();
    v_impact_ += h * m.gravity * (1.0 + m.max_friction) * lever;
    v_spin_ = 4.0 * h * r;
  }
  const int nv = m.vertex_count();
  if (!m.curved() && nv <= kSoaVertices) {
    soa_vertices_ = nv;
    for (int i = 0; i < nv; ++i) {
      vx_[i] = m.vertices[static_cast<std::size_t>(i)].x();
      vy_[i] = m.vertices[static_cast<std::size_t>(i)].y();
      vz_[i] = m.vertices[static_cast<std::size_t>(i)].z();
    }
    if (nv % 2 == 1) vx_[nv] = vx_[nv - 1], vy_[nv] = vy_[nv - 1], vz_[nv] = vz_[nv - 1];
  }
}

namespace {

double relative_gain(double before, double after) {
  return before > 0.0 ? (after - before) / before : (after > 0.0 ? after : 0.0);
}

// Leapfrog and rim steps: a corner the last step's solve pushed (warm, P_z > 0) stays in the contact set while
// it lies within `hold` of the floor, though above the touch tolerance. The leapfrog's bias holds
// such a corner's end height to second order only (leapfrog_bias: the solve's own change of the
// spin moves it by (a_n after - a_n before) d^2 / 8, ~1e-9 m a step on a rocking die): without
// this a pivot that drifted past the touch tolerance left the set, fell and landed again
// plastically, losing energy (the loss moved with the tolerance).
void keep_held(const DieModel& m, const RigidState& s, const ContactImpulses& warm, double hold, ContactSet& c) {
  for (int k = 0; k < warm.n && c.n < kMaxContacts; ++k) {
    const int v = warm.vertex[k];
    if (!(warm.P[k].z() > 0.0) || corner_height(m, s, v) > hold) continue;
    int at = 0;
    while (at < c.n && c.vertex[at] < v) ++at;
    if (at < c.n && c.vertex[at] == v) continue;
    for (int j = c.n; j > at; --j) c.vertex[j] = c.vertex[j - 1];
    c.vertex[at] = v;
    ++c.n;
  }
}

}  // namespace

// Trials of the shortened step's length (each a whole step) before taking the best one.
constexpr int kMaxTrials = 12;
// Halvings of a curved die's step whose support was capped (step()).
constexpr int kMaxHalvings = 4;

int FixedStepper::step(RigidState& s) { return step(s, kinetic_energy(*m_, s)); }

int FixedStepper::step(RigidState& s, double ke) {
  const DieModel& m = *m_;
  ContactSet c;
  if (s.position.z() <= m.bounding_radius + touch_tol_ && !(soa_vertices_ > 0 && soa_touching(s, c)))
    c = touching_corners(m, s, touch_tol_);
  // A curved die's too, within 1e-5 r: its rim steps hold only the lower of two touching rim
  // circles exactly on the floor (one bias for the solve), the other within ~w^2 r h^2 / 8 (4e-6 r
  // at 30 rad/s and 0.2 ms). With the flat dice's 1e-6 r the three-sided coin's second circle left
  // the set and landed again, located, 765 times a toss (2 016 without any hold; 8 at 1e-5 r).
  if ((leapfrog() || m.curved()) && warm_.n > 0)
    keep_held(m, s, warm_, (m.curved() ? 1e-5 : 1e-6) * m.bounding_radius, c);
  const bool relanded = land_window_ > 0.0;  // this is the step taken again (below)
  const bool struck = rim_strike_;  // ... or taken again with the rim struck (below)
  rim_strike_ = false;
  if (m.curved() && c.n > 0) add_face_tripod(s, c, land_window_, land_depth_, land_either_);
  land_window_ = land_depth_ = 0.0;
  land_either_ = false;
  const double E0 = ke + m.mass * m.gravity * s.position.z();  // mechanical_energy(m, s)
  // Impact first, at the instant of contact, on the velocity before gravity's kick: restitution
  // returns the approach speed the corner really had (after the kick it would return g h more,
  // and gain energy). Then (in each trial) gravity, then the plastic solve that holds the die up.
  // The impact depends only on the step's start, not on its length: solved once, shared by every
  // trial step.
  RigidState s0 = s;
  impact_ = false;
  geo_.valid = false;  // every solve of this step (its impact, each trial) shares s0.R and c
  Iw_start_ = world_inertia(m, s0.R);
  // The solves' set-up needs the same world inertia (the same expression of the same R): handed over.
  geo_.Iw = Iw_start_;
  geo_.iw_given = true;
  if (c.n > 0) {
    double un = 0.0;
    for (int i = 0; i < c.n; ++i) un = std::min(un, corner_velocity(m, s0, c.vertex[i]).z());
    impact_ = un < -impact_speed(s0);
    if (impact_)
      imp_ = struck ? strike_rim(s0, c) : apply_friction_impact(m, s0, c, /*restitution=*/true, nullptr, nullptr, &geo_);
  }
  // After the impact: every trial's energy check starts here (without one, s0 is s: E0).
  e_start_ = impact_ ? mechanical_energy(m, s0) : E0;
  if (leapfrog()) start_rot_.emplace(moments_, s0.R, Vec3(Iw_start_ * s0.omega), true);
  rims_new_ = false;
  slap_rims_ = 0;
  miss_rate_ = 0.0;
  hermite_ = false;
  // `impulse` (max_sink_): the step's length from its held corners' predicted sink, and what
  // they ask of the solve (try_step): the shallowest one's depth at the start, the deepest one's
  // (the energy check), and a_down_.
  a_down_ = 0.0;
  start_shallow_ = start_depth_max_ = 0.0;
  hold_ = max_sink_ > 0.0 && c.n > 0;
  h_ = hold_ ? predicted_step(s0, c) : h_ctrl_;
  if (hold_) {
    const Vec3 z_row = s0.R.row(2).transpose();
    double shallow = std::numeric_limits<double>::infinity();
    for (int i = 0; i < c.n; ++i) {
      const double depth =
          -(s0.position.z() + z_row.dot(m.vertices[static_cast<std::size_t>(c.vertex[i])]) - m.rounding);
      shallow = std::min(shallow, depth);
      start_depth_max_ = std::max(start_depth_max_, depth);
    }
    start_shallow_ = shallow > touch_tol_ ? shallow : 0.0;
  }
  try_step(s0, c, h_, a_, /*full=*/true);
  if (m.curved() && c.n > 0 && !rims_new_) {
    // A slap (slap_rims_): a touching rim whose lowest point, in the body, turns by more than
    // 90 deg along it over the full step's free motion after the start's solve (its tilt passes
    // through or near zero), the far half of it clear of the floor at the start. The full step
    // is then tried again as a slap's: its new contact the far half (slap_low), the curvature
    // impulse holding only the near half (support_low), and shortened to the far half's arrival,
    // where the next step strikes it (impact first, with restitution). If the far half does not
    // reach the floor in that step, the plain step stands.
    const Vec3& e1 = m.rims.perp;
    const Vec3 e2 = m.rims.axis.cross(e1);
    const Vec3 z0 = s0.R.row(2).transpose(), z1 = free_end_row_;
    const double a0 = z0.dot(e1), b0 = z0.dot(e2), a1 = z1.dot(e1), b1 = z1.dot(e2);
    const double n0 = std::sqrt(a0 * a0 + b0 * b0);
    for (int i = 0; i < c.n; ++i) {
      const int r = c.vertex[i] < 3 ? 0 : 1;
      if ((slap_rims_ & (1 << r)) || !(n0 > 0.0) || !(a0 * a1 + b0 * b1 < 0.0)) continue;
      slap_u_[r][0] = -a0 / n0;
      slap_u_[r][1] = -b0 / n0;
      if (s0.position.z() + slap_low(z0, r) > touch_tol_) slap_rims_ |= 1 << r;
    }
    if (slap_rims_ != 0) {
      try_step(s0, c, h_, a_, /*full=*/true);
      if (!(a_.G < -touch_tol_)) {
        ++slap_no_arrival;
        slap_rims_ = 0;
        try_step(s0, c, h_, a_, /*full=*/true);
      }
    }
  }
  const Attempt* done = &a_;
  double dt = h_;
  // The search for a new contact's instant (below), run again as the plain step's if a slap's
  // located step leaves the rest of its rim below the floor (then the far half was not the first
  // part to arrive: the lowest point ran round the rim, a roll, which the middle's support holds).
  const auto locate = [&] {
    done = &a_;
    dt = h_;
    if (!(a_.G < -touch_tol_)) return;
    // A corner not yet touching would end the step below the floor. The step is shortened to the
    // instant it touches: the length d whose whole step (gravity's kick g d, the contact solve,
    // the free motion) ends with that corner on the floor, G(d) = 0 (G: the lowest such corner's
    // height at the step's end). Each trial is a whole step, so the accepted one keeps every
    // property of a step (energy included). The trials' lengths: the root of the full step's model
    // of G (model_G: exact without contact, so one trial), corrected for a flat die by the support
    // solve's predicted share of the kick (predicted_miss: with corners in contact the plain model
    // missed by 10-1000 touch tolerances and the first trial almost never landed), then of the
    // model corrected by the last trial's measured miss (defect correction, while the model stays
    // bracketing), then Illinois on G itself in the bracket the trials have found.
    const Vec3 z_row = s0.R.row(2).transpose();
    double g_lo = std::numeric_limits<double>::infinity();
    if (m.curved()) {
      g_lo = s0.position.z() + curved_low(c, s0.R);
    } else {
      int j = 0;
      for (int i = 0; i < static_cast<int>(m.vertices.size()); ++i) {
        if (j < c.n && c.vertex[j] == i) {
          ++j;
          continue;
        }
        g_lo = std::min(g_lo, s0.position.z() + z_row.dot(m.vertices[i]) - m.rounding);
      }
    }
    double d_lo = 0.0, d_hi = h_, g_hi = a_.G;
    // The model's values at d_lo, d_hi and the next trial's d, each evaluated once (the model is a
    // fixed function during the search: the full step's motion).
    double mg_lo = model_G(c, 0.0), mg_hi = 0.0, mg_d = 0.0;
    bool modelled = mg_lo > 0.0, have_mg_d = false;
    double d = 0.5 * h_;
    if (modelled) {
      // A flat die's model at h_ is the full step itself: its G (lowest_flat of the same p, v, h_
      // and row: try_step_with's R_end row is bit for bit bottom_row(h_)), plus g (h_ - h_) h_ = 0.
      mg_hi = m.curved() ? model_G(c, h_) : a_.G;
      mg_d = mg_hi;
      // The first trial's length from the model corrected by the support solve's predicted
      // effect (predicted_miss), the search started from a cubic interpolant of the arriving
      // corner's motion (hermite_start). Both only move the first trial toward the root.
      double miss0 = 0.0;
      if (!m.curved()) {
        const Vec3 z_end = a_.s.R.row(2).transpose();
        int arg = -1;
        double low = std::numeric_limits<double>::infinity();
        int j = 0;  // c.vertex is ascending
        for (int i = 0; i < static_cast<int>(m.vertices.size()); ++i) {
          if (j < c.n && c.vertex[j] == i) {
            ++j;
            continue;
          }
          const double z = z_end.dot(m.vertices[i]);
          if (z < low) low = z, arg = i;
        }
        if (arg >= 0) {
          const Vec3 r0 = s0.R * m.vertices[arg], r1 = a_.s.R * m.vertices[arg];
          hq_[0] = r0.z();
          hq_[1] = full_w_.cross(r0).z();
          hq_[2] = r1.z();
          hq_[3] = a_.s.omega.cross(r1).z();
          hermite_ = true;
          if (c.n > 0) miss0 = predicted_miss(c, r0);
        }
      }
      d = model_root(c, miss0, 0.0, h_, corrected(mg_lo, miss0, 0.0), corrected(mg_hi, miss0, h_), mg_d);
      have_mg_d = true;
    }
    bool have_lo = false;
    int side = 0;
    done = nullptr;
    Attempt* trial = &b_;
    Attempt* lo = &lo_;
    for (int k = 0; k < kMaxTrials; ++k) {
      try_step(s0, c, d, *trial);
      ++located_trials;
      if (std::abs(trial->G) <= touch_tol_) {
        done = trial;
        dt = d;
        break;
      }
      const double span = d * (h_ - d);
      const double mgd = have_mg_d ? mg_d : model_G(c, d);
      have_mg_d = false;
      const double miss = span > 0.0 ? (trial->G - mgd) / span - miss_rate_ * d : 0.0;
      const bool above = trial->G > 0.0;
      if (above) {
        d_lo = d, g_lo = trial->G, mg_lo = mgd;
        std::swap(trial, lo);  // the attempts are large: swap who is which, not their contents
        have_lo = true;
      } else {
        d_hi = d, g_hi = trial->G, mg_hi = mgd;
      }
      // Defect correction (twice at most) while the corrected model brackets a root in [d_lo, d_hi].
      const double f_lo = modelled ? corrected(mg_lo, miss, d_lo) : 0.0;
      const double f_hi = modelled ? corrected(mg_hi, miss, d_hi) : 0.0;
      modelled = modelled && k < 2 && f_lo > 0.0 && f_hi <= 0.0;
      if (modelled) {
        double mg_next = mg_hi;
        const double next = model_root(c, miss, d_lo, d_hi, f_lo, f_hi, mg_next);
        if (next > d_lo && next < d_hi) {
          d = next;
          mg_d = mg_next;
          have_mg_d = true;
          continue;
        }
        modelled = false;
      }
      // Illinois on G itself (regula falsi halving the stale end's weight).
      if (above) {
        if (side == -1) g_hi *= 0.5;
        side = -1;
      } else {
        if (side == 1) g_lo *= 0.5;
        side = 1;
      }
      d = d_hi - g_hi * (d_hi - d_lo) / (g_hi - g_lo);
      if (!(d > d_lo && d < d_hi)) d = 0.5 * (d_lo + d_hi);
    }
    if (!done) {
      // Not within the tolerance in kMaxTrials trials (the touch is nearly tangential): the longest
      // trial that ends above the floor; the corner touches in the next step. Counted.
      ++located_capped;
      if (have_lo) {
        done = lo;
        dt = d_lo;
      } else {  // every trial ended below: the shortest, its corner lifted to the floor at the end (flat dice)
        try_step(s0, c, d_hi, *trial);
        ++located_trials;
        done = trial;
        dt = d_hi;
      }
    }
    ++located;
  };
  locate();
  if (!m.curved() && c.n > 0 && max_sink_ > 0.0) {
    // What the held corners sank in the accepted step, checked: more than max_sink_ (the start's
    // solve turned the die, or the acceleration changed within the step), the whole step again,
    // shorter by the sink's d^2 law (twice at most; not below the shortest step).
    const double h_min = h_max_ / kMinStepDivisor;
    for (int k = 0; k < 2; ++k) {
      double depth;
      const double sink = held_sink(s0, done->s, c, depth);
      if (!(sink > max_sink_) || !(h_ > h_min)) break;
      h_ = std::max(h_min, 0.9 * h_ * std::sqrt(max_sink_ / sink));
      ++sink_shortened;
      miss_rate_ = 0.0;
      hermite_ = false;
      try_step(s0, c, h_, a_, /*full=*/true);
      locate();
    }
  }
  if (!m.curved() && c.n > 0) {
    double depth;
    const double sink = held_sink(s0, done->s, c, depth);
    max_held_sink = std::max(max_held_sink, depth);
    if (sink > std::max(max_sink_, touch_tol_)) ++held_sinks;
    if (h_ < h_max_) ++short_steps;
  }
  // The accepted step halved (at most kMaxHalvings times) while its capped support
  // leaves the rims sinking (why it happens: below).
  const auto halve_while_capped = [&] {
    Attempt* buf = done == &b_ ? &lo_ : &b_;
    double d = dt;
    for (int k = 0; k < kMaxHalvings && done->to_halve(); ++k) {
      d *= 0.5;
      try_step(s0, c, d, *buf);
      done = buf;
      dt = d;
      buf = buf == &b_ ? &lo_ : &b_;
    }
    ++halved;
  };
  // A slap's step whose near half the capped support leaves sinking: halved as a plain
  // step would be, still a slap's (its end then before the far half's arrival).
  if (slap_rims_ != 0 && done->to_halve()) halve_while_capped();
  if (slap_rims_ != 0 && done->s.position.z() + rim_lowest(m, done->s.R) < -touch_tol_) {
    ++slap_rim_below;
    slap_rims_ = 0;
    try_step(s0, c, h_, a_, /*full=*/true);
    locate();
  }
  if (m.curved() && done->to_halve() && slap_rims_ == 0) {
    // (Not a slap's step: its end is the far half's arrival, which a halving would miss.)
    // The middle's support could not hold the rims on the floor without gaining energy beyond
    // the step's bound: the lowest point's height is far from quadratic over the step (a near-flat
    // coin spinning fast, its lowest point running round the rim: the slap). Shorter steps, halved
    // (at most kMaxHalvings times) until it holds; what is still below the floor then is lifted,
    // counted (overlap_fixes).
    halve_while_capped();
  }
  // A curved die's rims at the accepted step's end, below the floor by this (lifted at the end).
  const double below = m.curved() ? -(done->s.position.z() + rim_lowest(m, done->s.R)) : 0.0;
  if (m.curved() && c.n > 0 && !relanded && !struck) {
    // The accepted step still capped after the halvings (a clamp), or its rim ending below the
    // floor (a lift, at the end): in every case examined a coin landing or lying nearly flat (tilt
    // 1e-6 to 6e-5 rad) on one rim point, whose lowest point runs round the rim while the face comes
    // down. If the face's tripod reaches the floor within the full step at its approach speed, or
    // lies within the depth the lift would close, the step is taken again from its start with the
    // tripod in the contact set: struck at once, as a polyhedron's landing face is (what it
    // closes early is what the step would close anyway, at most the lift it replaces). Once. (The
    // discarded attempt's work counters, located, halved and the slap's, stay counted.)
    if (done->to_halve() || done->clamped || below > touch_tol_) {
      ContactSet wide = c;
      add_face_tripod(s, wide, h_, std::max(0.0, below));
      // Kind B (issue 13): the accepted step still clamps after the halvings, the coin within a
      // few mrad of flat, tumbling at 30-80 rad/s about a nearly horizontal axis: its rim's
      // lowest point jumps across the face within microseconds (a = 12 mm, tilt 3e-4, 46 rad/s:
      // the curvature of its height is a w^2 / tilt ~ 1e5 m/s^2), which no step of the halvings
      // (62.5 us) holds with an impulse that does no work. That is the face coming down: one
      // tripod point descends at ~a w (0.4-1 m/s, 0.5-65 um up) while the other rises, so the
      // rule above (both arriving) does not take it. It is struck as a face, the tripod joining
      // when one of its points reaches the floor within the step (the rising one takes an
      // impulse only if the strike turns it down). Kept only if the step taken again does better
      // than the clamp (and lift) it replaces: the tripod does not cover the arcs between its
      // points, and a face struck while an arc still comes down (a slap's face struck at 1 m/s,
      // CylinderImpulse.SlappingFaceIsStruck) can clamp and lift again; the stepper's state is
      // then restored and the step finished as it was.
      if (wide.n == c.n && done->clamped) {
        add_face_tripod(s, wide, h_, std::max(0.0, below), /*either=*/true);
        if (wide.n > c.n) {
          const FixedStepper kept = *this;  // (rare: a few in 10^4 tosses)
          const RigidState s_in = s;
          const auto before = corrections.total();
          land_window_ = h_;
          land_depth_ = std::max(0.0, below);
          land_either_ = true;
          ++flat_landed;
          const int n = step(s);
          if (corrections.total() - before < (below > touch_tol_ ? 2u : 1u)) {
            ++face_jumped;
            return n;
          }
          *this = kept;
          s = s_in;
          ++face_jump_declined;
        }
      }
      if (wide.n > c.n) {
        land_window_ = h_;
        land_depth_ = std::max(0.0, below);
        ++flat_landed;
        return step(s, ke);
      }
      // The face's tripod already struck by this step's impact, and an arc of the rim between its
      // points still coming down after it (restitution turned a fast spin over: strike_rim): the
      // step taken again with that arc struck too. Kept only if it counts fewer corrections than
      // this step would (a step with none to replace is not taken again: it could not be kept);
      // otherwise the state is restored and the step finished as it was.
      const auto replaced = (impact_ ? imp_.corrections.total() : 0u) + done->sup.corrections.total() +
                            (done->clamped ? 1u : 0u) + (below > touch_tol_ ? 1u : 0u);
      int rim;
      Vec3 p;
      double vz;
      if (replaced > 0 && impact_ && rim_most_approaching(s0, c, h_, rim, p, vz) && vz < -impact_speed(s0)) {
        const FixedStepper kept = *this;  // (rare: a few in 10^5 tosses)
        const RigidState s_in = s;
        const auto before = corrections.total();
        rim_strike_ = true;
        const int n = step(s);
        if (corrections.total() - before < replaced) {
          ++rim_struck;
          return n;
        }
        *this = kept;
        s = s_in;
        ++rim_strike_declined;
      }
    }
  }
  const Attempt& a = *done;
  s = a.s;
  rim_slip_ = a.slip;
  rim_slip_vertex_ = a.slip_vertex;
  if (a.impact) {
    ++impacts;
    corrections.add(a.imp.corrections);
    sweeps += static_cast<std::uint64_t>(a.imp.iterations);
    dual_solves += static_cast<std::uint64_t>(a.imp.dual_solves);
    exact_fallbacks += static_cast<std::uint64_t>(a.imp.exact_fallbacks);
    max_energy_gain = std::max(max_energy_gain, relative_gain(a.imp.energy_before, a.imp.energy_after));
  }
  // An accepted step whose support was capped (to gain no energy) is a clamp, counted
  // as the start's are (the step itself then holds the rims with less than the exact end gap).
  if (a.clamped) ++corrections.energy_clamps;
  if (c.n > 0) {
    corrections.add(a.sup.corrections);
    exact_fallbacks += static_cast<std::uint64_t>(a.sup.exact_fallbacks);
    sweeps += static_cast<std::uint64_t>(a.sup.iterations);
    max_energy_gain = std::max(max_energy_gain, relative_gain(a.sup.energy_before, a.sup.energy_after));
  }
  // (Only the used entries: ContactImpulses holds kMaxContacts of them.)
  warm_.n = a.next.n;
  for (int i = 0; i < a.next.n; ++i) {
    warm_.vertex[i] = a.next.vertex[i];
    warm_.P[i] = a.next.P[i];
  }
  dt_ = dt;
  if (adaptive_.tol > 0.0) adapt(s0, s, dt);
  slap_located_ = rims_new_ && dt < h_;
  if (slap_rims_ != 0 && dt < h_) ++slaps;
  end_ke_ = kinetic_energy(m, s);
  if (a.risen) {
    // A step whose held corners rose: no gain in the rest rules' energy, which adds the deepest
    // corner's depth to the COM height (try_step's check).
    max_energy_gain =
        std::max(max_energy_gain, relative_gain(E0 + m.mass * m.gravity * start_depth_max_ + split_gain(dt), a.held_e));
  } else {
    max_energy_gain =
        std::max(max_energy_gain, relative_gain(E0 + split_gain(dt), end_ke_ + m.mass * m.gravity * s.position.z()));
  }
  {
    // Plain E over the step (the lifts below are counted corrections, not the step's).
    const double mg = m.mass * m.gravity;
    const double plain = end_ke_ + mg * s.position.z();
    max_step_rise = std::max(max_step_rise, (plain - E0) / mg);
    max_rise_excess = std::max(max_rise_excess, relative_gain(E0 + mg * start_depth_max_ + split_gain(dt), plain));
  }
  if (a.rise_dropped) ++rise_dropped;
  if (!m.curved() && a.G < -touch_tol_) {
    // Only a located step whose every trial ended below the floor (locate: the shortest taken)
    // ends with a corner not in c deeper than the touch tolerance: the COM is lifted by its depth,
    // the corner put on the floor, counted (overlap_fixes; the step is also located_capped).
    s.position.z() -= a.G;
    ++corrections.overlap_fixes;
  }
  if (m.curved()) {
    // The rims end every step within the touch tolerance of the floor or above it; where the step
    // left them deeper (a slapping rim, whose plain solve does not push, rim_support; a bias not
    // bracketed; a search out of trials) the COM is lifted by the residual, counted. (The energy
    // check above is of the step itself; the lift's m g dz is that counted correction.)
    const double pen = below;  // (s is the accepted attempt's state, unchanged since)
    max_penetration = std::max(max_penetration, pen);
    if (pen > touch_tol_) {
      s.position.z() += pen;
      ++corrections.overlap_fixes;
    }
  }
  return c.n;
}

}  // namespace dicesim

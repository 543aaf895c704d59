// A world toss (issue 41): several dice and static obstacles, `impulse` physics. Each die is its
// own ImpulseRun (exact flights, the floor's impact law, sustained contact, rest), advanced window
// by window; a window ends before any die can touch another die or an obstacle. The window is
// conservative advancement: a die's points move no faster than its energy allows,
//   |v_point| <= sqrt(2 E / m) + r sqrt(2 E / I_min),  E = kinetic + m g (z - z_rest),
// a bound that holds for the rest of the toss (no impact and no step gains energy), so a window of
// gap / (V_a + V_b) never lets a pair pass through each other at any spin. A pair whose gap falls
// within the touch tolerance is struck at that instant: a die against an obstacle by the floor's
// own law turned to the obstacle's face (every corner within the tolerance together); two dice by
// the one-point law of two bodies (pair_impact.hpp). Slow contacts (under the stepper's impact
// threshold, 4 g contact_step) are plastic, as the floor's sustained contact is. A die that rests
// stays where it is as an obstacle until another strikes it. The toss ends when every die rests.
#include "sim/models/world_toss.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "sim/body/world.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/convex_distance.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/pair_impact.hpp"
#include "sim/dynamics/rest.hpp"
#include "sim/models/fidelity_models.hpp"
#include "sim/models/impulse_run.hpp"

namespace dicesim {

namespace {

constexpr int kMaxDice = 6;
// A die held still off its rest (leaning on a wall or another die, cocked; lying on an obstacle's
// top) never rests on a face by the floor's rule: held this long, kinetic energy below
// kStillEnergy m g r, the toss is unresolved. A safety cap on contacts besides.
constexpr double kStillTime = 0.5;      // s
constexpr double kStillEnergy = 1e-4;   // of m g r
constexpr int kMaxInteractions = 200000;

// A contact between die i and something else at one instant.
struct Touch {
  double gap = 0.0;              // m, between the rounded surfaces (< 0: overlapping)
  Vec3 normal = Vec3::UnitZ();   // unit, from the other body into die i
  Vec3 point = Vec3::Zero();     // world, on die i's surface
  bool degenerate = false;
  bool exact = true;             // false: gap is only a lower bound (far apart), normal and point unset
};

PlacedHull placed(const World& w, int k, const RigidState& s) {
  const DieModel& d = w.dice[static_cast<std::size_t>(k)];
  return PlacedHull{d.vertices, d.face_normals, w.die_edges[static_cast<std::size_t>(k)], s.R, s.position};
}

PlacedHull placed(const ObstaclePiece& p) {
  return PlacedHull{p.corners, p.face_normals, p.edge_dirs, Mat3::Identity(), Vec3::Zero()};
}

Touch touch_piece(const World& w, int k, const RigidState& s, const ObstaclePiece& p) {
  const DieModel& d = w.dice[static_cast<std::size_t>(k)];
  Touch t;
  if (p.plane) {
    double lo = std::numeric_limits<double>::infinity();
    int low = 0;
    for (int v = 0; v < d.vertex_count(); ++v) {
      const double h = p.normal.dot(s.position + s.R * d.vertices[static_cast<std::size_t>(v)]);
      if (h < lo) lo = h, low = v;
    }
    t.gap = lo - p.offset - d.rounding;
    t.normal = p.normal;
    t.point = s.position + s.R * d.vertices[static_cast<std::size_t>(low)] - d.rounding * p.normal;
    return t;
  }
  const Separation sep = separation(placed(w, k, s), placed(p));
  t.gap = sep.distance - d.rounding;
  t.normal = -sep.normal;
  t.point = sep.point_a - d.rounding * t.normal;
  t.degenerate = sep.degenerate;
  return t;
}

Touch touch_die(const World& w, int i, const RigidState& si, int j, const RigidState& sj) {
  const DieModel& a = w.dice[static_cast<std::size_t>(i)];
  const DieModel& b = w.dice[static_cast<std::size_t>(j)];
  const Separation sep = separation(placed(w, i, si), placed(w, j, sj));
  Touch t;
  t.gap = sep.distance - a.rounding - b.rounding;
  t.normal = -sep.normal;
  // Midway between the two rounded surfaces' witness points.
  t.point = 0.5 * ((sep.point_a - a.rounding * t.normal) + (sep.point_b + b.rounding * t.normal));
  t.degenerate = sep.degenerate;
  return t;
}

// How fast die k's points can move, two ways:
//  * for the rest of the toss: sqrt(2 E / m) + r sqrt(2 E / I_min) (see the file's comment), with
//    5 % spare for the stepper's rounding-level gains;
//  * while it flies, until its next floor contact (found exactly, as its own flight finds it):
//    the COM's velocity v + g t, and the spin's part at most r sqrt(2 K_rot / I_min) (K_rot is
//    constant in flight).
// Pairs take the longer of the two windows each bound allows.
struct Reach {
  double any = 0.0;       // the whole-toss bound (m/s); 0: at rest (only others strike it)
  bool flying = false;    // in flight now (not in the stepper's hands)
  double free_for = 0.0;  // flying: how long it stays clear of the floor at least (s)
  Vec3 v = Vec3::Zero();  // flying: the COM's velocity now
  double spin = 0.0;      // flying: the spin's bound on a point's speed relative to the COM
};

// How far ahead a flight's floor contact is searched for the flight bound (s).
constexpr double kFlightHorizon = 1.0;

Reach reach_of(const ImpulseRun& r) {
  Reach out;
  if (r.state != RunState::Running) return out;
  const DieModel& d = *r.m;
  const RigidState& s = r.s;
  const double z_rest = *std::min_element(d.face_height.begin(), d.face_height.end());
  const double k_rot = 0.5 * s.omega.dot(world_inertia(d, s.R) * s.omega);
  const double e = kinetic_energy(d, s) + d.mass * d.gravity * std::max(0.0, s.position.z() - z_rest);
  const double i_min = d.principal_moments.minCoeff();
  out.any = 1.05 * (std::sqrt(2.0 * e / d.mass) + d.bounding_radius * std::sqrt(2.0 * e / i_min)) + 1e-12;
  if (!r.sustained) {
    // Until its next floor contact (the exact search its own flight will make) it only flies.
    const Flight flight(d, s);
    const double limit = std::min(kFlightHorizon, d.max_time - r.t);
    const ContactSearch c = flight.next_contact(limit);
    out.flying = true;
    out.free_for = c.outcome == ContactSearch::Outcome::Contact ? c.t : limit;
    out.v = s.velocity;
    out.spin = 1.0000001 * d.bounding_radius * std::sqrt(2.0 * k_rot / i_min);
  }
  return out;
}

// The longest window in which points approaching at `closing` + accel t (m/s) cannot close `gap`.
double window_for(double gap, double closing, double accel) {
  if (accel <= 0.0) return closing > 0.0 ? gap / closing : std::numeric_limits<double>::infinity();
  return 2.0 * gap / (closing + std::sqrt(closing * closing + 2.0 * accel * gap));
}

// A lower bound on the gap between die k (its bounding sphere) and a polyhedron piece (its
// axis-aligned box).
double box_gap(const World& w, const DieModel& d, const RigidState& s, std::size_t p) {
  const Vec3 out = (w.piece_lo[p] - s.position).cwiseMax(s.position - w.piece_hi[p]).cwiseMax(0.0);
  return out.norm() - d.bounding_radius;
}

// A pair this far apart (a lower bound) is not measured exactly: the bound is the gap.
Touch far_apart(double gap) {
  Touch t;
  t.gap = gap;
  t.exact = false;
  return t;
}

// Frame turning n to +z (the floor law's normal), as a rotation matrix.
Mat3 to_normal_frame(const Vec3& n) { return Quat::FromTwoVectors(n, Vec3::UnitZ()).toRotationMatrix(); }

// Die k against a fixed piece at a touch: the floor's law turned to the piece's face. Every corner
// of the die within `tol` of the piece strikes together; if none (an edge across an edge, a
// pyramid's tip on a face), the one witness point.
// `witness` counts the nearest point's own strike when the corners' left it approaching.
ImpactResult strike_piece(const World& w, int k, RigidState& s, const ObstaclePiece& p, int material, const Touch& t,
                          double tol, bool restitution, std::uint64_t& witness) {
  const DieModel& d = w.die_against[static_cast<std::size_t>(k)][static_cast<std::size_t>(material)];
  ContactSet c;
  std::array<Vec3, kMaxContacts> r{};
  const PlacedHull hull = placed(p);
  for (int v = 0; v < d.vertex_count() && c.n < kMaxContacts; ++v) {
    const Vec3 x = s.position + s.R * d.vertices[static_cast<std::size_t>(v)];
    const double dist = p.plane ? p.normal.dot(x) - p.offset : point_distance(hull, x);
    if (dist - d.rounding <= tol) {
      c.vertex[c.n] = v;
      r[static_cast<std::size_t>(c.n)] = x - t.normal * d.rounding - s.position;
      ++c.n;
    }
  }
  if (c.n == 0) {
    c.n = 1;
    c.vertex[0] = 0;
    r[0] = t.point - s.position;
  }
  const Mat3 Q = to_normal_frame(t.normal);
  RigidState q{Q * s.position, Q * s.velocity, Q * s.R, Q * s.omega};
  for (int i = 0; i < c.n; ++i) r[static_cast<std::size_t>(i)] = Q * r[static_cast<std::size_t>(i)];
  ImpactResult imp = apply_friction_impact_at(d, q, c, r.data(), restitution);
  // Corners near the piece need not include the nearest point (a corner near a face's plane beside
  // an edge that touches): if that still approaches, it is struck on its own too.
  const Vec3 w_point = Q * (t.point - s.position);
  if ((q.velocity + q.omega.cross(w_point)).z() < 0.0) {
    ContactSet one;
    one.n = 1;
    one.vertex[0] = c.vertex[0];
    const ImpactResult more = apply_friction_impact_at(d, q, one, &w_point, restitution);
    imp.corrections.add(more.corrections);
    imp.normal_impulse += more.normal_impulse;
    imp.energy_after = more.energy_after;
    ++witness;
  }
  s.velocity = Q.transpose() * q.velocity;
  s.omega = Q.transpose() * q.omega;
  return imp;
}

// The fastest any corner of the die moves along `dir` now (m/s; 0 if none does).
double fastest_corner(const DieModel& d, const RigidState& s, const Vec3& dir) {
  const double along = s.velocity.dot(dir);
  const Vec3 spin_dir = s.omega.cross(dir);  // (w x r) . dir = r . (dir x w) = -r . (w x dir)
  double fastest = 0.0;
  for (const Vec3& c : d.vertices) fastest = std::max(fastest, along - (s.R * c).dot(spin_dir));
  return fastest;
}

// How soon a corner of the die, at its speed now plus `extra` toward the plane {x : n . x = level}
// (n pointing into the die), would reach it: min over corners of height / approach (+inf if none
// approaches). A far corner approaching fast does not shorten it as a near one does.
double closing_time(const DieModel& d, const RigidState& s, const Vec3& n, double level, double extra) {
  const Vec3 spin_dir = s.omega.cross(n);
  const double along = s.velocity.dot(n);
  double soonest = std::numeric_limits<double>::infinity();
  for (const Vec3& c : d.vertices) {
    const Vec3 r = s.R * c;
    const double approach = -(along - r.dot(spin_dir)) + extra;
    if (approach <= 0.0) continue;
    const double height = std::max(0.0, n.dot(s.position + r) - d.rounding - level);
    soonest = std::min(soonest, height / approach);
  }
  return soonest;
}

Vec3 point_velocity(const RigidState& s, const Vec3& x) { return s.velocity + s.omega.cross(x - s.position); }

Mat3 inverse_inertia(const DieModel& d, const Mat3& R) {
  return R * d.principal_moments.cwiseInverse().asDiagonal() * R.transpose();
}

}  // namespace

TossResult run_world(const DieModel& m, const std::vector<RigidState>& starts, const std::vector<double>& tiebreaks,
                     TossProbe* probe) {
  const World& w = *m.world;
  const int n = w.size();
  TossResult res;
  std::vector<ImpulseRun> runs;
  runs.reserve(static_cast<std::size_t>(n));
  double r_min = std::numeric_limits<double>::infinity(), step = 0.0;
  for (int k = 0; k < n; ++k) {
    const DieModel& d = w.dice[static_cast<std::size_t>(k)];
    runs.emplace_back(d, starts[static_cast<std::size_t>(k)], tiebreaks[static_cast<std::size_t>(k)]);
    r_min = std::min(r_min, d.bounding_radius);
    step = std::max(step, d.contact_step);
  }
  const double tol = 1e-6 * r_min;                       // a touch, as the floor's corner set
  const double v_slow = sustained_contact_speed(m, step);  // slower contacts are plastic (the stepper's threshold)
  const double t_touching = 0.05 * step;                 // the window while a pair touches without approaching
  // Approaching: faster than rounding (a plastic strike leaves the point at -1e-17 m/s or so).
  const double v_still = 1e-9 * std::sqrt(m.gravity * r_min);
  // A gap this small is near (m): the bounds' windows would crawl (a die sliding along a wall, dice
  // resting side by side, a struck die moving off slowly), so the window is a guess, checked after.
  const double near = 0.1 * r_min;
  const double t_guess = 0.5 * step;  // the longest guessed window (s)
  // An overlap found after a window is lifted out; deeper than the floor's bound on a held corner's
  // sink in a step (held_corner_sink: 1e-4 r) it is counted as a correction (contact_overlaps).
  const double sink = 1e-4 * r_min;
  const auto overlap_found = [&](ImpulseRun& r, double gap) {
    if (probe) probe->max_overlap = std::max(probe->max_overlap, -gap);
    if (gap < -sink) ++r.corrections.contact_overlaps;
  };

  // The start must be possible: no die inside another or inside an obstacle.
  for (int i = 0; i < n; ++i) {
    const RigidState& si = runs[static_cast<std::size_t>(i)].s;
    for (std::size_t p = 0; p < w.pieces.size(); ++p)
      if (touch_piece(w, i, si, w.pieces[p]).gap < -tol) return res;  // Invalid
    for (int j = i + 1; j < n; ++j)
      if (touch_die(w, i, si, j, runs[static_cast<std::size_t>(j)].s).gap < -tol) return res;
  }

  // Pairs whose window was a guess (dice i, j, or die i and piece p; j or p -1), and the runs at
  // the window's start to take it again from.
  struct RiskyPair {
    int i, j, p;
    double gap;  // at the window's start
  };
  constexpr int kMaxRisky = 32;
  constexpr int kMaxHalvings = 24;
  std::array<RiskyPair, kMaxRisky> risky_pairs{};
  int risky_n = 0;
  std::vector<ImpulseRun> saved;
  // Does a risky pair (all of them, if there were more than kMaxRisky) now overlap deeper than the sink?
  const auto too_deep = [&] {
    // Deeper than the sink, and deeper than at the window's start.
    const auto deep_piece = [&](int i, std::size_t p, double start) {
      const double gap = touch_piece(w, i, runs[static_cast<std::size_t>(i)].s, w.pieces[p]).gap;
      return gap < -sink && gap < start;
    };
    const auto deep_pair = [&](int i, int j, double start) {
      const double gap = touch_die(w, i, runs[static_cast<std::size_t>(i)].s, j, runs[static_cast<std::size_t>(j)].s).gap;
      return gap < -sink && gap < start;
    };
    if (risky_n > kMaxRisky) {
      for (int i = 0; i < n; ++i) {
        for (std::size_t p = 0; p < w.pieces.size(); ++p)
          if (deep_piece(i, p, 0.0)) return true;
        for (int j = i + 1; j < n; ++j)
          if (deep_pair(i, j, 0.0)) return true;
      }
      return false;
    }
    for (int k = 0; k < risky_n; ++k) {
      const RiskyPair& q = risky_pairs[static_cast<std::size_t>(k)];
      if (q.j >= 0 ? deep_pair(q.i, q.j, q.gap) : deep_piece(q.i, static_cast<std::size_t>(q.p), q.gap)) return true;
    }
    return false;
  };

  double T = 0.0;
  int interactions = 0;
  std::uint64_t witness_strikes = 0;
  std::array<double, kMaxDice> still_since;  // per die: since when it has been held still off its rest (-1: moving)
  still_since.fill(-1.0);
  std::uint64_t windows = 0;
  bool unresolved = false;
  std::array<Reach, kMaxDice> reach{};
  while (!unresolved) {
    bool any_running = false;
    for (int k = 0; k < n; ++k) {
      const ImpulseRun& r = runs[static_cast<std::size_t>(k)];
      reach[static_cast<std::size_t>(k)] = reach_of(r);
      any_running = any_running || r.state == RunState::Running;
      double& since = still_since[static_cast<std::size_t>(k)];
      const bool still = r.state == RunState::Running &&
                         kinetic_energy(*r.m, r.s) < kStillEnergy * r.m->mass * r.m->gravity * r.m->bounding_radius;
      if (!still) since = -1.0;
      else if (since < 0.0) since = T;
      else if (T - since > kStillTime) unresolved = true;
    }
    if (unresolved) break;
    if (!any_running) break;
    if (T >= m.max_time) {
      unresolved = true;
      break;
    }

    // The window: as long as no pair can close its gap; pairs touching now are struck first.
    double window = m.max_time - T;
    bool struck = false;
    // safe(gap): the longest window the pair's bounds allow for that gap; approach(): how soon the
    // pair's corners, at their speeds now, would close it; strike(): strikes the pair if it
    // approaches (true).
    // A window longer than a pair's bound allows (nearly touching, below) is checked afterwards.
    risky_n = 0;
    const auto risky = [&](int i, int j, int p, double gap) {
      if (risky_n < kMaxRisky) risky_pairs[static_cast<std::size_t>(risky_n)] = {i, j, p, gap};
      ++risky_n;
    };
    // thick: the thinner body's least width; closing: the pair's whole-toss speed bound.
    const auto consider = [&](const Touch& t, auto&& safe, auto&& approach, auto&& strike, int i, int j, int p,
                              double thick, double closing) {
      if (t.gap > tol) {
        double dt = safe(t.gap);
        if (t.gap < near) {
          // Near: half what the pair's corners at their speeds now take to close the gap, at most
          // t_guess, and never so long that the bound could carry one body through half the other.
          // Checked after the window (and located by halving if it went deeper than the sink).
          const double guess = std::min({0.5 * approach(), t_guess, (t.gap + 0.5 * thick) / closing});
          if (guess > dt) {
            dt = guess;
            risky(i, j, p, t.gap);
          }
        }
        window = std::min(window, dt);
        return;
      }
      if (strike()) {
        struck = true;
      } else {
        window = std::min(window, t_touching);
        risky(i, j, p, t.gap);
      }
    };
    for (int i = 0; i < n && !struck; ++i) {
      ImpulseRun& ri = runs[static_cast<std::size_t>(i)];
      const Reach& ai = reach[static_cast<std::size_t>(i)];
      const double vi = ai.any;
      if (vi == 0.0) continue;  // a resting die: only others strike it
      const DieModel& di = *ri.m;
      for (std::size_t p = 0; p < w.pieces.size() && !struck; ++p) {
        const ObstaclePiece& piece = w.pieces[p];
        const double lower = piece.plane ? 0.0 : box_gap(w, di, ri.s, p);
        if (lower > std::max(tol, vi * window)) continue;
        const Touch t = lower > near ? far_apart(lower) : touch_piece(w, i, ri.s, piece);
        if (t.degenerate && probe) ++probe->narrow_degenerate;
        const auto safe = [&](double gap) {
          double dt = gap / vi;
          if (ai.flying) {  // gravity's part of the approach, along the piece's normal only (if known)
            const double g_in = t.exact ? m.gravity * t.normal.z() : m.gravity;
            const double v_in = t.exact ? std::max(0.0, -ai.v.dot(t.normal)) : ai.v.norm();
            const double flown = window_for(gap, v_in + ai.spin, std::max(0.0, g_in));
            dt = std::max(dt, std::min(flown, ai.free_for));
          }
          return dt;
        };
        // The other surface's plane at the touch: n . x = n . point - gap.
        const auto approach = [&] { return closing_time(di, ri.s, t.normal, t.normal.dot(t.point) - t.gap, 0.0); };
        consider(t, safe, approach, [&] {
          const double un = point_velocity(ri.s, t.point).dot(t.normal);
          if (!(un < -v_still)) {
            if (!(t.gap < -tol)) return false;
            overlap_found(ri, t.gap);  // overlapping though moving apart: lifted out, then looked at again
            ri.s.position -= t.gap * t.normal;
            return true;
          }
          const bool bounce = -un > v_slow;
          const ImpactResult imp = strike_piece(w, i, ri.s, piece, w.piece_material[p], t, tol, bounce, witness_strikes);
          ri.corrections.add(imp.corrections);
          if (t.gap < -tol) {  // found overlapping: struck, and lifted out along the normal
            overlap_found(ri, t.gap);
            ri.s.position -= t.gap * t.normal;
          }
          if (bounce) ++ri.bounces;
          ri.after_impact = false;
          ri.since_impact = 0.0;
          if (probe) ++probe->interactions;
          return true;
        }, i, -1, static_cast<int>(p), std::min(w.die_width[static_cast<std::size_t>(i)], w.piece_width[p]), vi);
      }
      for (int j = 0; j < n && !struck; ++j) {
        if (j == i) continue;
        ImpulseRun& rj = runs[static_cast<std::size_t>(j)];
        const Reach& aj = reach[static_cast<std::size_t>(j)];
        const double vj = aj.any;
        if (j < i && vj > 0.0) continue;  // a pair of running dice once, from its first
        const double closing = vi + vj;
        const double far = (ri.s.position - rj.s.position).norm() - di.bounding_radius - rj.m->bounding_radius;
        if (far > std::max(tol, closing * window)) continue;
        const Touch t = far > near ? far_apart(far) : touch_die(w, i, ri.s, j, rj.s);
        if (t.degenerate && probe) ++probe->narrow_degenerate;
        const auto safe = [&](double gap) {
          double dt = gap / closing;
          if (ai.flying && aj.flying) {  // both fly: gravity moves them alike, their relative velocity is constant
            const double v_in = t.exact ? std::max(0.0, -(ai.v - aj.v).dot(t.normal)) : (ai.v - aj.v).norm();
            const double flown = window_for(gap, v_in + ai.spin + aj.spin, 0.0);
            dt = std::max(dt, std::min(flown, std::min(ai.free_for, aj.free_for)));
          } else if (ai.flying && vj == 0.0) {  // one flies at one at rest: as at an obstacle
            const double v_in = t.exact ? std::max(0.0, -ai.v.dot(t.normal)) : ai.v.norm();
            const double flown = window_for(gap, v_in + ai.spin, std::max(0.0, t.exact ? m.gravity * t.normal.z() : m.gravity));
            dt = std::max(dt, std::min(flown, ai.free_for));
          }
          return dt;
        };
        const auto approach = [&] {
          // Each die's corners against the other's surface plane, the other closing at its fastest.
          // (t.point is midway between the two surfaces.)
          const double level_j = t.normal.dot(t.point) - 0.5 * t.gap;     // j's surface, seen from i
          const double level_i = -(t.normal.dot(t.point) + 0.5 * t.gap);  // i's surface, seen from j (normal -n)
          return std::min(closing_time(di, ri.s, t.normal, level_j, fastest_corner(*rj.m, rj.s, t.normal)),
                          closing_time(*rj.m, rj.s, -t.normal, level_i, fastest_corner(di, ri.s, -t.normal)));
        };
        consider(t, safe, approach, [&] {
          const double un = (point_velocity(ri.s, t.point) - point_velocity(rj.s, t.point)).dot(t.normal);
          const double share = rj.m->mass / (di.mass + rj.m->mass);
          if (!(un < -v_still)) {
            if (!(t.gap < -tol)) return false;
            overlap_found(ri, t.gap);  // overlapping though moving apart: moved apart, then looked at again
            ri.s.position -= share * t.gap * t.normal;
            rj.s.position += (1.0 - share) * t.gap * t.normal;
            return true;
          }
          const bool bounce = -un > v_slow;
          const DieModel& dj = *rj.m;
          const double e = bounce ? 0.5 * (w.die_restitution[static_cast<std::size_t>(i)] +
                                           w.die_restitution[static_cast<std::size_t>(j)])
                                  : 0.0;
          const double mu =
              0.5 * (w.die_friction[static_cast<std::size_t>(i)] + w.die_friction[static_cast<std::size_t>(j)]);
          const PairImpactResult imp =
              apply_pair_impact(PairSide{&ri.s.velocity, &ri.s.omega, 1.0 / di.mass, inverse_inertia(di, ri.s.R),
                                         t.point - ri.s.position},
                                PairSide{&rj.s.velocity, &rj.s.omega, 1.0 / dj.mass, inverse_inertia(dj, rj.s.R),
                                         t.point - rj.s.position},
                                t.normal, e, mu);
          ri.corrections.add(imp.corrections);
          if (t.gap < -tol) {  // found overlapping: struck, and moved apart along the normal, the lighter more
            overlap_found(ri, t.gap);
            ri.s.position -= share * t.gap * t.normal;
            rj.s.position += (1.0 - share) * t.gap * t.normal;
          }
          if (bounce) ++ri.bounces, ++rj.bounces;
          for (ImpulseRun* r : {&ri, &rj}) {
            r->after_impact = false;
            r->since_impact = 0.0;
            if (r->state == RunState::Settled) {  // struck at rest: it moves again from here
              r->state = RunState::Running;
              r->sustained = true;
              r->t = T;
              if (probe) ++probe->woken;
            }
          }
          if (probe) ++probe->interactions;
          return true;
        }, i, j, -1, std::min(w.die_width[static_cast<std::size_t>(i)], w.die_width[static_cast<std::size_t>(j)]), closing);
      }
    }
    if (struck) {
      if (++interactions > kMaxInteractions) unresolved = true;
      for (const ImpulseRun& r : runs)
        if (r.bounces >= r.m->max_bounces) unresolved = true;
      continue;  // gaps and bounds again from the struck state
    }

    // Advance every running die to the window's end. A window longer than its bounds allow (a
    // risky pair) is taken again half as long while such a pair ends deeper than the sink bound:
    // the contact located, as the floor's stepper locates a new corner's.
    if (risky_n > 0) saved.assign(runs.begin(), runs.end());
    for (int tries = 0;; ++tries) {
      const double t_end = std::min(T + window, m.max_time);
      ++windows;
      for (ImpulseRun& r : runs) {
        if (r.state != RunState::Running) continue;
        r.advance(t_end, probe);
      }
      if (risky_n == 0 || tries == kMaxHalvings || !too_deep()) {
        T = t_end;
        break;
      }
      std::copy(saved.begin(), saved.end(), runs.begin());
      window *= 0.5;
      if (probe) ++probe->windows_halved;
    }
    for (const ImpulseRun& r : runs)
      if (r.state == RunState::Unresolved) unresolved = true;
  }
  if (probe) {
    probe->windows += windows;
    probe->witness_strikes += witness_strikes;
  }

  // The toss's result from every die's.
  int tuple = 0;
  res.bounces = 0;
  res.t_end = T;
  for (int k = 0; k < n; ++k) {
    ImpulseRun& r = runs[static_cast<std::size_t>(k)];
    const TossResult one = r.result(k == 0 ? probe : nullptr);
    if (probe && k > 0) add_stepper_stats(*probe, r.stats);
    res.bounces += one.bounces;
    res.corrections.add(one.corrections);
    if (one.status != TossStatus::Settled) unresolved = true;
    else tuple += one.outcome * w.stride[static_cast<std::size_t>(k)];
  }
  if (unresolved) {
    res.status = TossStatus::Unresolved;
    return res;
  }
  res.status = TossStatus::Settled;
  res.outcome = w.tuple_outcome[static_cast<std::size_t>(tuple)];
  res.face = m.outcome_labels[static_cast<std::size_t>(res.outcome)];
  res.face_index = -1;
  return res;
}

}  // namespace dicesim

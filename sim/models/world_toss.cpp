// A world toss (issue 41): several dice and static obstacles, `impulse` physics. Each die is its
// own ImpulseRun (exact flights, the floor's impact law, sustained contact, rest), advanced window
// by window; a window ends before any die can touch another die or an obstacle. The window is
// conservative advancement: a die's points move no faster than its energy allows,
//   |v_point| <= sqrt(2 E / m) + r sqrt(2 E / I_min),  E = kinetic + m g (z - z_rest),
// a bound that holds for the rest of the toss (no impact and no step gains energy), and its
// bounding sphere's gap closes no faster than its COM moves, so no pair passes through each other
// at any spin. A near pair's window is a guess, checked after it and halved while the pair went
// too deep. A pair whose gap falls within the touch tolerance is struck at that instant over its
// contact patch (contact_patch.hpp): a die against an obstacle, or slowly against a die at rest,
// by the floor's own law turned to the touch's normal; two moving dice by the law of two bodies
// (pair_impact.hpp). Slow contacts (under the stepper's impact threshold, 4 g contact_step) are
// plastic, as the floor's sustained contact is. A die that rests stays where it is as an obstacle
// until another strikes it fast. The toss ends when every die rests. docs/world.md says more.
#include "sim/models/world_toss.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

#include "sim/body/world.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/contact_patch.hpp"
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
// Strikes at one instant are Gauss-Seidel sweeps over the contacts there (see run_world): their cap.
constexpr int kMaxSweeps = 16;

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

// What a toss remembers of a pair between windows: the narrow phase's warm start, and the gap at
// the last window's start (for the next guess's secant). Direct-mapped by the pair (die i and die
// j, or die i and piece p, in that order): a slot is taken over by the last pair measured there.
struct PairMemo {
  SeparationCache sep;
  double gap = 0.0, at = -1.0;  // at < 0: none
  Vec3 axis = Vec3::Zero();     // the last exact touch's normal (zero: none)
  // The impulses of the pair's last strike at its patch's points (in the touch's frame), to start
  // the next strike's Gauss-Seidel sweeps from: a die lying on another or on an obstacle's top is
  // struck at the same points window after window.
  std::array<Vec3, 4> warm{};  // a patch has at most four points
  int warm_n = 0;
};

class PairMemos {
 public:
  PairMemo* die(int i, int j) { return slot((std::uint64_t(i) << 32) | std::uint64_t(j)); }
  PairMemo* piece(int i, std::size_t p) { return slot((std::uint64_t(i) << 32) | (std::uint64_t(p) + kMaxDice)); }

 private:
  static constexpr int kBits = 6;
  PairMemo* slot(std::uint64_t key) {
    const std::size_t k = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - kBits));
    if (keys_[k] != key + 1) {
      keys_[k] = key + 1;
      memos_[k] = PairMemo{};
    }
    return &memos_[k];
  }
  std::array<std::uint64_t, 1u << kBits> keys_{};  // 0: empty
  std::array<PairMemo, 1u << kBits> memos_{};
};

// A lower bound on the gap between two bodies from any unit axis n (from b toward a): how far
// a's corners lie beyond b's along it, less the roundings. At the last normal of a pair that has
// moved a little, it is nearly the gap itself, for a few dot products instead of GJK.
double axis_gap(std::span<const Vec3> a, double ra, std::span<const Vec3> b, double rb, const Vec3& n) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec3& x : a) lo = std::min(lo, n.dot(x));
  for (const Vec3& y : b) hi = std::max(hi, n.dot(y));
  return lo - hi - ra - rb;
}

Touch touch_piece(const World& w, int k, const RigidState& s, const ObstaclePiece& p, SeparationCache* cache = nullptr) {
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
  const Separation sep = separation(placed(w, k, s), placed(p), cache);
  t.gap = sep.distance - d.rounding;
  t.normal = -sep.normal;
  t.point = sep.point_a - d.rounding * t.normal;
  t.degenerate = sep.degenerate;
  return t;
}

Touch touch_die(const World& w, int i, const RigidState& si, int j, const RigidState& sj,
                SeparationCache* cache = nullptr) {
  const DieModel& a = w.dice[static_cast<std::size_t>(i)];
  const DieModel& b = w.dice[static_cast<std::size_t>(j)];
  const Separation sep = separation(placed(w, i, si), placed(w, j, sj), cache);
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
  double com = 0.0;       // the whole-toss bound on the COM's speed, sqrt(2 E / m) (m/s)
  bool flying = false;    // in flight now (not in the stepper's hands)
  double free_for = 0.0;  // flying: how long it stays clear of the floor at least (s)
  Vec3 v = Vec3::Zero();  // flying: the COM's velocity now
  double spin = 0.0;      // flying: the spin's bound on a point's speed relative to the COM
};

Reach reach_of(ImpulseRun& r, TossProbe* probe) {
  Reach out;
  // A flight's start checks for rest first (as the run's own would, at once).
  if (r.state == RunState::Running && !r.sustained && !r.flight && !r.settles_now(probe)) {
    const PhaseTimer timer(probe, Phase::Search);
    r.start_flight(probe);
  }
  if (r.state != RunState::Running) return out;
  const DieModel& d = *r.m;
  const RigidState& s = r.s;
  const double z_rest = *std::min_element(d.face_height.begin(), d.face_height.end());
  const double k_rot = 0.5 * s.omega.dot(world_inertia(d, s.R) * s.omega);
  const double e = kinetic_energy(d, s) + d.mass * d.gravity * std::max(0.0, s.position.z() - z_rest);
  const double i_min = d.principal_moments.minCoeff();
  out.com = 1.05 * std::sqrt(2.0 * e / d.mass) + 1e-12;
  out.any = out.com + 1.05 * d.bounding_radius * std::sqrt(2.0 * e / i_min);
  if (!r.sustained) {
    // Until its next floor contact (its own flight's, searched once at the flight's start) it only
    // flies. (A search that ended without a contact found none before it ended.)
    out.flying = true;
    out.free_for = r.flight->t0 + r.flight->contact.t - r.t;
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

// Bounding spheres: a die stays inside the sphere of its bounding radius about its COM however it
// spins, so a sphere's gap closes only as fast as the COMs move. Each window below is how long a
// sphere gap `gap` surely stays open:
//  * for the rest of the toss, at the COM's energy bound (Reach::com);
//  * while the dice fly (until the first one's next floor contact), along their exact COM motion,
//    then at the energy bound for what is left.
// Two flying dice: gravity moves both COMs alike, so their relative position d + v t is a straight
// line; the window is when it first comes within R (the radii's sum) of zero.
double spheres_window(const Reach& a, const Reach& b, const Vec3& d, double R) {
  const double gap = d.norm() - R;
  const double both = a.com + b.com;
  double dt = gap / both;
  if (!(a.flying && b.flying)) return dt;
  const double f = std::min(a.free_for, b.free_for);
  const Vec3 v = b.v - a.v;
  const double qa = v.squaredNorm(), qb = d.dot(v), qc = d.squaredNorm() - R * R;
  const double disc = qb * qb - qa * qc;
  if (qa > 0.0 && qb < 0.0 && disc >= 0.0) {
    const double hit = qc / (-qb + std::sqrt(disc));  // the smaller root of qa t^2 + 2 qb t + qc
    if (hit < f) return std::max(dt, hit);
  }
  return std::max(dt, f + std::max(0.0, (d + v * f).norm() - R) / both);
}

// A flying die's sphere against a fixed surface `gap` away along unit n (pointing into the die;
// n = 0: direction unknown, any): its COM closes at v(t) . (-n) <= v_in + g_in t until the floor
// contact, then at the energy bound.
double sphere_fixed_window(const Reach& a, double gap, const Vec3& n, double g) {
  double dt = gap / a.com;
  if (!a.flying) return dt;
  const bool known = n.squaredNorm() > 0.5;
  const double v_in = known ? std::max(0.0, -a.v.dot(n)) : a.v.norm();
  const double g_in = known ? std::max(0.0, g * n.z()) : g;
  const double flown = window_for(gap, v_in, g_in);
  if (flown < a.free_for) return std::max(dt, flown);
  const double closed = v_in * a.free_for + 0.5 * g_in * a.free_for * a.free_for;
  return std::max(dt, a.free_for + std::max(0.0, gap - closed) / a.com);
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

// A die's corners in the world (the centres of its rounded corners).
class WorldCorners {
 public:
  WorldCorners(const DieModel& d, const RigidState& s) {
    const std::size_t n = d.vertices.size();
    Vec3* out = n <= inline_.size() ? inline_.data() : (heap_.resize(n), heap_.data());
    for (std::size_t v = 0; v < n; ++v) out[v] = s.position + s.R * d.vertices[v];
    corners_ = std::span<const Vec3>(out, n);
  }
  std::span<const Vec3> corners() const { return corners_; }

 private:
  std::array<Vec3, 32> inline_;
  std::vector<Vec3> heap_;
  std::span<const Vec3> corners_;
};

// Where die i touches a piece at `t` (contact_patch.hpp), within tol; the witness point if the
// patch came out empty. The piece's surface plane at the touch is n . x = n . point - gap.
ContactPatch piece_patch(const World& w, int i, const RigidState& s, const ObstaclePiece& p, const Touch& t,
                         double tol) {
  const DieModel& d = w.dice[static_cast<std::size_t>(i)];
  const WorldCorners mine(d, s);
  const double level_b = t.normal.dot(t.point) - t.gap;
  ContactPatch patch = contact_patch({mine.corners(), d.rounding},
                                     {p.plane ? std::span<const Vec3>{} : std::span<const Vec3>(p.corners), 0.0},
                                     t.normal, level_b + t.gap, level_b, tol);
  if (patch.n == 0) patch.points[static_cast<std::size_t>(patch.n++)] = t.point;
  return patch;
}

// Where dice i and j touch at `t` (t.point lies midway between their surfaces).
ContactPatch dice_patch(const World& w, int i, const RigidState& si, int j, const RigidState& sj, const Touch& t,
                        double tol) {
  const DieModel& di = w.dice[static_cast<std::size_t>(i)];
  const DieModel& dj = w.dice[static_cast<std::size_t>(j)];
  const WorldCorners ci(di, si), cj(dj, sj);
  const double mid = t.normal.dot(t.point);
  ContactPatch patch = contact_patch({ci.corners(), di.rounding}, {cj.corners(), dj.rounding}, t.normal,
                                     mid + 0.5 * t.gap, mid - 0.5 * t.gap, tol);
  if (patch.n == 0) patch.points[static_cast<std::size_t>(patch.n++)] = t.point;
  return patch;
}

// The least normal velocity of die i relative to the other body (its velocity and spin; zero for
// a fixed one) over a patch's points: under -v_still, the pair approaches.
double patch_approach(const ContactPatch& patch, const RigidState& si, const RigidState* sj, const Vec3& n,
                      int* fastest = nullptr) {
  double un = std::numeric_limits<double>::infinity();
  for (int q = 0; q < patch.n; ++q) {
    const Vec3& x = patch.points[static_cast<std::size_t>(q)];
    Vec3 rel = si.velocity + si.omega.cross(x - si.position);
    if (sj) rel -= sj->velocity + sj->omega.cross(x - sj->position);
    const double u = rel.dot(n);
    if (u < un) {
      un = u;
      if (fastest) *fastest = q;
    }
  }
  return un;
}

// Die i against a fixed body (an obstacle, or a die held at rest) over a contact patch: the floor's
// law turned to the touch's normal, every point of the patch together. `d` carries the pair's
// materials. If the patch's solve leaves the witness point approaching, that point is struck on
// its own too (counted in `witness`).
ImpactResult strike_fixed(const DieModel& d, RigidState& s, const Touch& t, const ContactPatch& patch,
                          bool restitution, std::uint64_t& witness, PairMemo& memo) {
  ContactSet c;
  std::array<Vec3, kMaxContacts> r{};
  const Mat3 Q = to_normal_frame(t.normal);
  for (int q = 0; q < patch.n && c.n < kMaxContacts; ++q) {
    c.vertex[c.n] = q;  // uniform materials: any corner's; the index matches the warm start's
    r[static_cast<std::size_t>(c.n++)] = Q * (patch.points[static_cast<std::size_t>(q)] - s.position);
  }
  RigidState q{Q * s.position, Q * s.velocity, Q * s.R, Q * s.omega};
  ContactImpulses warm, out;
  warm.n = restitution ? 0 : memo.warm_n;  // (a stale start that would add energy is dropped by the law)
  for (int k = 0; k < warm.n; ++k) {
    warm.vertex[k] = k;
    warm.P[k] = memo.warm[static_cast<std::size_t>(k)];
  }
  ImpactResult imp = apply_friction_impact_at(d, q, c, r.data(), restitution, &warm, &out);
  memo.warm_n = std::min(out.n, static_cast<int>(memo.warm.size()));
  for (int k = 0; k < memo.warm_n; ++k) memo.warm[static_cast<std::size_t>(k)] = out.P[k];
  const Vec3 w_point = Q * (t.point - s.position);
  if ((q.velocity + q.omega.cross(w_point)).z() < 0.0) {
    ContactSet one;
    one.n = 1;
    one.vertex[0] = 0;
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

// How soon a corner of the die would reach the plane {x : n . x = level} (n pointing into the die)
// at its velocity now relative to the other body there (`other`'s rigid motion at the corner's
// place; none: a fixed body): min over corners of height / approach (+inf if none approaches).
// A far corner approaching fast does not shorten it as a near one does.
double closing_time(const DieModel& d, const RigidState& s, const Vec3& n, double level, const RigidState* other) {
  double soonest = std::numeric_limits<double>::infinity();
  for (const Vec3& c : d.vertices) {
    const Vec3 r = s.R * c;
    Vec3 rel = s.velocity + s.omega.cross(r);
    if (other) rel -= other->velocity + other->omega.cross(s.position + r - other->position);
    const double approach = -rel.dot(n);
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
  // The window while a pair touches without approaching: it starts at 0.05 contact steps, doubles
  // after each such window taken whole (up to t_guess below), and is the length taken after one
  // that had to be halved: a die lying on an obstacle's top or on another die waits in windows as
  // long as its checks allow.
  const double t_touching = 0.05 * step;
  // A gap this small is near (m): the bounds' windows would crawl (a die sliding along a wall, dice
  // resting side by side, a struck die moving off slowly), so the window is a guess, checked after.
  const double near = 0.1 * r_min;
  const double t_guess = 0.5 * step;  // the longest guessed window (s)
  // Approaching: fast enough to sink a tenth of the touch tolerance within the longest window a
  // touching pair takes (t_guess). Slower, a strike would only chase what is left of the last one
  // (a die wedged between two bodies: strike after strike at one instant).
  const double v_still = 0.1 * tol / t_guess;
  double touch_window = t_touching;
  // An overlap found after a window is lifted out; deeper than the floor's bound on a held corner's
  // sink in a step (held_corner_sink: 1e-4 r) it is counted as a correction (contact_overlaps).
  const double sink = 1e-4 * r_min;
  const auto overlap_found = [&](ImpulseRun& r, double gap) {
    if (probe) probe->max_overlap = std::max(probe->max_overlap, -gap);
    if (gap < -sink) ++r.corrections.contact_overlaps;
  };

  PairMemos memos;

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
      const double gap = touch_piece(w, i, runs[static_cast<std::size_t>(i)].s, w.pieces[p], &memos.piece(i, p)->sep).gap;
      return gap < -sink && gap < start;
    };
    const auto deep_pair = [&](int i, int j, double start) {
      const double gap =
          touch_die(w, i, runs[static_cast<std::size_t>(i)].s, j, runs[static_cast<std::size_t>(j)].s, &memos.die(i, j)->sep).gap;
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
  // Strikes at one instant are Gauss-Seidel sweeps over the contacts there: a die wedged between
  // two bodies may have each slow strike push it into the other for ever. After kMaxSweeps at one
  // instant its slow contacts are left touching for the window (and its check), counted.
  int sweeps = 0;
  bool sweeps_capped = false;
  std::uint64_t witness_strikes = 0;
  std::array<double, kMaxDice> still_since;  // per die: since when it has been held still off its rest (-1: moving)
  still_since.fill(-1.0);
  std::uint64_t windows = 0;
  bool unresolved = false;
  std::array<Reach, kMaxDice> reach{};
  while (!unresolved) {
    bool any_running = false;
    for (int k = 0; k < n; ++k) {
      ImpulseRun& r = runs[static_cast<std::size_t>(k)];
      reach[static_cast<std::size_t>(k)] = reach_of(r, probe);
      // A die that rests by the floor's rule may still rock on its face (its energy below every
      // way off it); it waits where it is, and still: the others strike a body that does not move.
      if (r.state == RunState::Settled) {
        r.s.velocity.setZero();
        r.s.omega.setZero();
      }
      any_running = any_running || r.state == RunState::Running;
    }
    if (!any_running) break;
    if (T >= m.max_time) {
      unresolved = true;
      break;
    }

    // The window: as long as no pair can close its gap; pairs touching now are struck first.
    double window = m.max_time - T;
    bool by_touch = false;  // the window is touch_window (a touching pair's)
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
                              double thick, double closing, PairMemo& memo) {
      if (t.gap > tol) {
        double dt = safe(t.gap);
        if (t.gap < near) {
          // Near: what the pair's corners at their speeds now take to close the gap, or what the
          // gap's own fall since the last window's start takes (its secant: a corner's speed
          // toward the other's surface plane may overstate how fast a gap between an edge and an
          // edge closes), whichever is longer (the touch located as the secant method would: a
          // pair that arrives ends the window touching, one whose approach slows takes another);
          // a gap that did not fall over the last window allows twice that window (a corner
          // turning toward the other's plane beside it need not meet it);
          // at most t_guess, and never so long that the bound could carry one body through half
          // the other. Checked after the window (and located by halving if it went deeper than
          // the sink).
          double predicted = approach();
          if (memo.at >= 0.0 && memo.at < T) {
            const double last = T - memo.at;
            predicted = std::max(predicted, memo.gap > t.gap ? t.gap * last / (memo.gap - t.gap) : 2.0 * last);
          }
          const double guess = std::min({predicted, t_guess, (t.gap + 0.5 * thick) / closing});
          if (guess > dt) {
            dt = guess;
            risky(i, j, p, t.gap);
          }
        }
        if (dt < window) window = dt, by_touch = false;
        memo.gap = t.gap;
        memo.at = T;
        return;
      }
      memo.at = -1.0;
      if (strike()) {
        struck = true;
      } else {
        if (touch_window < window) window = touch_window, by_touch = true;
        risky(i, j, p, t.gap);
      }
    };
    for (int i = 0; i < n && !struck; ++i) {
      ImpulseRun& ri = runs[static_cast<std::size_t>(i)];
      const Reach& ai = reach[static_cast<std::size_t>(i)];
      const double vi = ai.any;
      if (vi == 0.0) continue;  // a resting die: only others strike it
      const DieModel& di = *ri.m;
      // Die i against piece p, whose gap is at least `lower`.
      const auto piece_pair = [&](std::size_t p, double lower) {
        const ObstaclePiece& piece = w.pieces[p];
        // The bounding sphere's window (0: the sphere touches the piece already).
        const double sphere_gap =
            piece.plane ? piece.normal.dot(ri.s.position) - piece.offset - di.bounding_radius : lower;
        const double sphere_dt =
            sphere_gap > 0.0 ? sphere_fixed_window(ai, sphere_gap, piece.plane ? piece.normal : Vec3::Zero(), m.gravity)
                             : 0.0;
        if (sphere_dt >= window) return;
        PairMemo* memo = memos.piece(i, p);
        double bound = lower;
        if (bound <= near && !piece.plane) {
          // Along the pair's last normal, or (none yet) from the piece's box toward the die's centre.
          Vec3 axis = memo->axis;
          if (axis.squaredNorm() == 0.0) {
            const Vec3 c = ri.s.position;
            axis = c - c.cwiseMax(w.piece_lo[p]).cwiseMin(w.piece_hi[p]);
            if (axis.squaredNorm() > 0.0) axis.normalize();
          }
          if (axis.squaredNorm() > 0.0)
            bound = std::max(bound, axis_gap(WorldCorners(di, ri.s).corners(), di.rounding, piece.corners, 0.0, axis));
        }
        // The window the bounds allow at gap `gap` (tt: the touch, for its normal if exact).
        const auto safe_for = [&](const Touch& tt, double gap) {
          double dt = std::max(gap / vi, sphere_dt);
          if (ai.flying) {  // gravity's part of the approach, along the piece's normal only (if known)
            const double g_in = tt.exact ? m.gravity * tt.normal.z() : m.gravity;
            const double v_in = tt.exact ? std::max(0.0, -ai.v.dot(tt.normal)) : ai.v.norm();
            const double flown = window_for(gap, v_in + ai.spin, std::max(0.0, g_in));
            dt = std::max(dt, std::min(flown, ai.free_for));
          }
          return dt;
        };
        // Even at its lower bound, a pair that allows the window as it stands is not measured
        // (a guess only lengthens a pair's window).
        if (bound > tol && safe_for(far_apart(bound), bound) >= window) return;
        const Touch t = bound > near ? far_apart(bound) : touch_piece(w, i, ri.s, piece, &memo->sep);
        if (t.exact) memo->axis = t.normal;
        if (t.degenerate && probe) ++probe->narrow_degenerate;
        const auto safe = [&](double gap) { return safe_for(t, gap); };
        // The other surface's plane at the touch: n . x = n . point - gap.
        const auto approach = [&] { return closing_time(di, ri.s, t.normal, t.normal.dot(t.point) - t.gap, nullptr); };
        consider(t, safe, approach, [&] {
          // Every point of the patch (the witness alone may be any point of a face in contact).
          const ContactPatch patch = piece_patch(w, i, ri.s, piece, t, tol);
          const double un = patch_approach(patch, ri.s, nullptr, t.normal);
          if (!(un < -v_still)) {
            if (!(t.gap < -tol)) return false;
            overlap_found(ri, t.gap);  // overlapping though moving apart: lifted out, then looked at again
            ri.s.position -= t.gap * t.normal;
            ri.moved();
            return true;
          }
          const bool bounce = -un > v_slow;
          if (!bounce && sweeps_capped) return false;  // left touching: checked after the window
          const DieModel& against =
              w.die_against[static_cast<std::size_t>(i)][static_cast<std::size_t>(w.piece_material[p])];
          const ImpactResult imp = strike_fixed(against, ri.s, t, patch, bounce, witness_strikes, *memo);
          ri.corrections.add(imp.corrections);
          if (t.gap < -tol) {  // found overlapping: struck, and lifted out along the normal
            overlap_found(ri, t.gap);
            ri.s.position -= t.gap * t.normal;
          }
          if (bounce) ++ri.bounces;
          ri.after_impact = false;
          ri.since_impact = 0.0;
          ri.moved();
          if (probe) ++probe->interactions;
          return true;
        }, i, -1, static_cast<int>(p), std::min(w.die_width[static_cast<std::size_t>(i)], w.piece_width[p]), vi, *memo);
      };
      // Half-spaces each; the polyhedra through the tree, those whose box the bound reaches.
      for (const int p : w.plane_pieces) {
        if (struck) break;
        piece_pair(static_cast<std::size_t>(p), 0.0);
      }
      // How far a piece's box may be and still be reached within the window: by any point at the
      // whole-toss bound, or by the bounding sphere (sphere_fixed_window, any direction).
      const auto reach_now = [&] {
        if (struck) return -1.0;
        double far = std::min(vi, ai.com) * window;
        if (ai.flying) {
          const double f = std::min(window, ai.free_for);
          far = std::min(far, ai.v.norm() * f + 0.5 * m.gravity * f * f + ai.com * (window - f));
        }
        return std::max(tol, far);
      };
      if (!struck)
        w.piece_tree.visit_near(ri.s.position, di.bounding_radius, reach_now(), [&](int p, double lower) {
          piece_pair(static_cast<std::size_t>(p), lower);
          return reach_now();
        });
      for (int j = 0; j < n && !struck; ++j) {
        if (j == i) continue;
        ImpulseRun& rj = runs[static_cast<std::size_t>(j)];
        const Reach& aj = reach[static_cast<std::size_t>(j)];
        const double vj = aj.any;
        if (j < i && vj > 0.0) continue;  // a pair of running dice once, from its first
        const double closing = vi + vj;
        const double far = (ri.s.position - rj.s.position).norm() - di.bounding_radius - rj.m->bounding_radius;
        if (far > std::max(tol, closing * window)) continue;
        // The bounding spheres' window (0: they overlap already); a die at rest is a fixed sphere.
        double sphere_dt = 0.0;
        if (far > 0.0)
          sphere_dt = vj == 0.0 ? sphere_fixed_window(ai, far, Vec3::Zero(), m.gravity)
                                : spheres_window(ai, aj, rj.s.position - ri.s.position,
                                                 di.bounding_radius + rj.m->bounding_radius);
        if (sphere_dt >= window) continue;
        PairMemo* memo = memos.die(i, j);
        double bound = far;
        if (bound <= near && memo->axis.squaredNorm() > 0.0)
          bound = std::max(bound, axis_gap(WorldCorners(di, ri.s).corners(), di.rounding, WorldCorners(*rj.m, rj.s).corners(),
                                           rj.m->rounding, memo->axis));
        const auto safe_for = [&](const Touch& tt, double gap) {
          double dt = std::max(gap / closing, sphere_dt);
          if (ai.flying && aj.flying) {  // both fly: gravity moves them alike, their relative velocity is constant
            const double v_in = tt.exact ? std::max(0.0, -(ai.v - aj.v).dot(tt.normal)) : (ai.v - aj.v).norm();
            const double flown = window_for(gap, v_in + ai.spin + aj.spin, 0.0);
            dt = std::max(dt, std::min(flown, std::min(ai.free_for, aj.free_for)));
          } else if (ai.flying && vj == 0.0) {  // one flies at one at rest: as at an obstacle
            const double v_in = tt.exact ? std::max(0.0, -ai.v.dot(tt.normal)) : ai.v.norm();
            const double flown =
                window_for(gap, v_in + ai.spin, std::max(0.0, tt.exact ? m.gravity * tt.normal.z() : m.gravity));
            dt = std::max(dt, std::min(flown, ai.free_for));
          }
          return dt;
        };
        if (bound > tol && safe_for(far_apart(bound), bound) >= window) continue;  // as for a piece
        const Touch t = bound > near ? far_apart(bound) : touch_die(w, i, ri.s, j, rj.s, &memo->sep);
        if (t.exact) memo->axis = t.normal;
        if (t.degenerate && probe) ++probe->narrow_degenerate;
        const auto safe = [&](double gap) { return safe_for(t, gap); };
        const auto approach = [&] {
          // Each die's corners against the other's surface plane, relative to the other's motion
          // there. (t.point is midway between the two surfaces.)
          const double level_j = t.normal.dot(t.point) - 0.5 * t.gap;     // j's surface, seen from i
          const double level_i = -(t.normal.dot(t.point) + 0.5 * t.gap);  // i's surface, seen from j (normal -n)
          return std::min(closing_time(di, ri.s, t.normal, level_j, &rj.s),
                          closing_time(*rj.m, rj.s, -t.normal, level_i, &ri.s));
        };
        consider(t, safe, approach, [&] {
          // Every point of the patch (the witness alone may be any point of a face in contact).
          const ContactPatch patch = dice_patch(w, i, ri.s, j, rj.s, t, tol);
          int fastest = 0;
          const double un = patch_approach(patch, ri.s, &rj.s, t.normal, &fastest);
          // A die at rest is held by the floor: all the correction goes to the moving one.
          const double share = rj.state == RunState::Settled ? 1.0 : rj.m->mass / (di.mass + rj.m->mass);
          if (!(un < -v_still)) {
            if (!(t.gap < -tol)) return false;
            overlap_found(ri, t.gap);  // overlapping though moving apart: moved apart, then looked at again
            ri.s.position -= share * t.gap * t.normal;
            rj.s.position += (1.0 - share) * t.gap * t.normal;
            ri.moved();
            rj.moved();
            return true;
          }
          const bool bounce = -un > v_slow;
          if (!bounce && sweeps_capped) return false;  // left touching: checked after the window
          if (!bounce && rj.state == RunState::Settled) {
            // A slow contact with a die at rest: the floor's friction holds that die. (The plastic
            // push of a contact under 4 g h could slide it, at most, v^2 / (2 mu g) on its face:
            // half a millimetre at mu = 0.4.) Die i is struck against it held where it lies, at
            // every point of contact, as against an obstacle, and it stays at rest.
            const DieModel& against = w.die_against[static_cast<std::size_t>(i)][static_cast<std::size_t>(
                w.die_pair_material[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)])];
            const ImpactResult imp = strike_fixed(against, ri.s, t, patch, /*restitution=*/false, witness_strikes, *memo);
            ri.corrections.add(imp.corrections);
            if (t.gap < -tol) {
              overlap_found(ri, t.gap);
              ri.s.position -= t.gap * t.normal;
            }
            ri.after_impact = false;
            ri.since_impact = 0.0;
            ri.moved();
            if (probe) ++probe->interactions, ++probe->held_at_rest;
            return true;
          }
          const DieModel& dj = *rj.m;
          if (!bounce) {
            // A slow contact between two moving dice (one leaning or lying on the other, both
            // sliding): every touching point is struck plastically with the two-body law in turn,
            // sweep after sweep until none approaches (Gauss-Seidel over the points, as a contact
            // solver's); one point struck alone would turn the die about it and drive the next
            // corner in. After kMaxSweeps sweeps, what still approaches is left to the window, counted.
            const double mu =
                0.5 * (w.die_friction[static_cast<std::size_t>(i)] + w.die_friction[static_cast<std::size_t>(j)]);
            const Mat3 inv_i = inverse_inertia(di, ri.s.R), inv_j = inverse_inertia(dj, rj.s.R);
            bool approaching = true;
            for (int sweep = 0; sweep < kMaxSweeps && approaching; ++sweep) {
              approaching = false;
              for (int q = 0; q < patch.n; ++q) {
                const Vec3& x = patch.points[static_cast<std::size_t>(q)];
                if (!((point_velocity(ri.s, x) - point_velocity(rj.s, x)).dot(t.normal) < -v_still)) continue;
                approaching = true;
                const PairImpactResult imp =
                    apply_pair_impact(PairSide{&ri.s.velocity, &ri.s.omega, 1.0 / di.mass, inv_i, x - ri.s.position},
                                      PairSide{&rj.s.velocity, &rj.s.omega, 1.0 / dj.mass, inv_j, x - rj.s.position},
                                      t.normal, 0.0, mu);
                ri.corrections.add(imp.corrections);
              }
            }
            if (approaching && probe) ++probe->sweeps_capped;
          } else {
            // An impact: the one-point law of two bodies at the patch's fastest approaching point.
            const double e = 0.5 * (w.die_restitution[static_cast<std::size_t>(i)] +
                                    w.die_restitution[static_cast<std::size_t>(j)]);
            const double mu =
                0.5 * (w.die_friction[static_cast<std::size_t>(i)] + w.die_friction[static_cast<std::size_t>(j)]);
            const Vec3& x = patch.points[static_cast<std::size_t>(fastest)];
            const PairImpactResult imp =
                apply_pair_impact(PairSide{&ri.s.velocity, &ri.s.omega, 1.0 / di.mass, inverse_inertia(di, ri.s.R),
                                           x - ri.s.position},
                                  PairSide{&rj.s.velocity, &rj.s.omega, 1.0 / dj.mass, inverse_inertia(dj, rj.s.R),
                                           x - rj.s.position},
                                  t.normal, e, mu);
            ri.corrections.add(imp.corrections);
          }
          if (t.gap < -tol) {  // found overlapping: struck, and moved apart along the normal, the lighter more
            overlap_found(ri, t.gap);
            ri.s.position -= share * t.gap * t.normal;
            rj.s.position += (1.0 - share) * t.gap * t.normal;
          }
          if (bounce) ++ri.bounces, ++rj.bounces;
          for (ImpulseRun* r : {&ri, &rj}) {
            r->after_impact = false;
            r->since_impact = 0.0;
            r->moved();
            if (r->state == RunState::Settled) {  // struck at rest: it moves again from here
              r->state = RunState::Running;
              r->sustained = true;
              r->t = T;
              if (probe) ++probe->woken;
            }
          }
          if (probe) ++probe->interactions;
          return true;
        }, i, j, -1, std::min(w.die_width[static_cast<std::size_t>(i)], w.die_width[static_cast<std::size_t>(j)]), closing,
           *memo);
      }
    }
    if (struck) {
      if (++sweeps == kMaxSweeps) {
        sweeps_capped = true;
        if (probe) ++probe->sweeps_capped;
      }
      if (++interactions > kMaxInteractions) unresolved = true;
      for (const ImpulseRun& r : runs)
        if (r.bounces >= r.m->max_bounces) unresolved = true;
      continue;  // gaps and bounds again from the struck state
    }

    sweeps = 0;
    sweeps_capped = false;
    // Held still: judged once this instant's strikes are done (before them, a die lying on an
    // obstacle carries what gravity gave it over the last window, which the strikes take away).
    for (int k = 0; k < n; ++k) {
      const ImpulseRun& r = runs[static_cast<std::size_t>(k)];
      double& since = still_since[static_cast<std::size_t>(k)];
      const bool still = r.state == RunState::Running &&
                         kinetic_energy(*r.m, r.s) < kStillEnergy * r.m->mass * r.m->gravity * r.m->bounding_radius;
      if (!still) since = -1.0;
      else if (since < 0.0) since = T;
      else if (T - since > kStillTime) unresolved = true;
    }
    if (unresolved) break;

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
        if (by_touch) touch_window = tries == 0 ? std::min(t_guess, 2.0 * touch_window) : window;
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

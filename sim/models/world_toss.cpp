// A world toss (issue 41): several dice and static obstacles, `impulse` physics. Each die is its
// own ImpulseRun (exact flights, the floor's impact law, sustained contact, rest), advanced window
// by window; a window ends before any die can touch another die or an obstacle. The window is
// conservative advancement: a die's points move no faster than its energy allows,
//   |v_point| <= sqrt(2 E / m) + r sqrt(2 E / I_min),  E = kinetic + m g (z - z_rest),
// a bound that holds for the rest of the toss (no impact and no step gains energy), and its
// bounding sphere's gap closes no faster than its COM moves, so no pair passes through each other
// at any spin. A near pair's window is a guess, checked after it and taken again shorter while the
// pair went too deep. A pair whose gap falls within the touch tolerance is struck at that instant
// over its contact patch (contact_patch.hpp): a die against an obstacle, or slowly against a die
// at rest, by the floor's own law turned to the touch's normal; two moving dice by the law of two
// bodies (pair_impact.hpp). Slow contacts (under the stepper's impact threshold, 4 g contact_step) are
// plastic, as the floor's sustained contact is. A die that rests stays where it is as an obstacle
// until another strikes it fast, and so does a die perched (held still off its rest by the bodies
// it touches). The toss ends when every die rests. docs/world.md says more.
#include "sim/models/world_toss.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "sim/body/world.hpp"
#include "sim/dynamics/contact.hpp"
#include "sim/dynamics/pair_impact.hpp"
#include "sim/models/impulse_run.hpp"
#include "sim/models/fidelity_models.hpp"
#include "sim/models/world_contacts.hpp"
#include "sim/models/world_windows.hpp"

namespace dicesim {

namespace {

// A die held still off its rest (leaning on a wall or another die, cocked; lying on an obstacle's
// top) never rests on a face by the floor's rule: held this long, kinetic energy below
// kStillEnergy m g r, the toss is unresolved (unless perched first: run_world). A safety cap on
// contacts besides.
constexpr double kStillTime = 0.5;      // s
constexpr double kStillEnergy = 1e-4;   // of m g r
constexpr int kMaxInteractions = 200000;
// Strikes at one instant are Gauss-Seidel sweeps over the contacts there (see run_world): their cap.
constexpr int kMaxSweeps = 16;

}  // namespace

TossResult run_world(const DieModel& m, const std::vector<RigidState>& starts, const std::vector<double>& tiebreaks,
                     TossProbe* probe) {
  using namespace world_detail;
  const World& w = *m.world;
  const int n = w.size();
  TossResult res;
  // The runs, their copies at a risky window's start, and the dice's corners: buffers kept by the
  // thread from toss to toss (no allocation per toss; every toss fills what it reads).
  thread_local std::vector<ImpulseRun> runs, saved;
  thread_local std::array<std::vector<Vec3>, kMaxDice> corner_buf;
  runs.clear();
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
  // The window while a pair touches without approaching: it starts at 0.05 contact steps, grows
  // after each such window taken whole (up to t_guess below), and is the length taken after one
  // that had to be taken again shorter: a die lying on an obstacle's top or on another die waits
  // in windows as long as its checks allow.
  const double t_touching = 0.05 * step;
  // A gap this small is near (m): the bounds' windows would crawl (a die sliding along a wall, dice
  // resting side by side, a struck die moving off slowly), so the window is a guess, checked after.
  // (0.2 r: a die bouncing off a craps backboard crawled past its pyramids 1.5-3 mm away in windows
  // of gap / (3 |v|); 0.1 r took 8 % more instructions per craps toss, 0.3 r 1 % fewer than 0.2 r.)
  const double near = 0.2 * r_min;
  const double t_guess = 0.5 * step;  // the longest guessed window (s)
  // ... of a pair that flies (two flying dice, or a flying die and a fixed body): its motion is the
  // exact flights' until a floor contact, smooth. (Twice t_guess: 3.6 % fewer instructions per craps
  // toss, 2.5 % per tray toss, where dice thrown together fly in near contact.)
  const double t_guess_flying = 2.0 * t_guess;
  // Approaching: fast enough to sink a tenth of the touch tolerance within the longest window a
  // touching pair takes (t_guess). Slower, a strike would only chase what is left of the last one
  // (a die wedged between two bodies: strike after strike at one instant).
  const double v_still = 0.1 * tol / t_guess;
  double touch_window = t_touching;
  double touch_growth = 2.0;
  // An overlap found after a window is lifted out; deeper than the floor's bound on a held corner's
  // sink in a step (held_corner_sink: 1e-4 r) it is counted as a correction (contact_overlaps).
  const double sink = 1e-4 * r_min;
  const auto overlap_found = [&](ImpulseRun& r, double gap) {
    if (probe) probe->max_overlap = std::max(probe->max_overlap, -gap);
    if (gap < -sink) ++r.corrections.contact_overlaps;
  };

  PairMemos memos;
  const auto still = [](const ImpulseRun& r) {
    return kinetic_energy(*r.m, r.s) < kStillEnergy * r.m->mass * r.m->gravity * r.m->bounding_radius;
  };
  // Each die's place, stamped: a new stamp whenever it may have moved (a window, a strike's lift,
  // a window taken again). A pair's exact touch is kept with the stamps it was measured at and
  // reused while they hold: a risky pair measured after its window is met again at the next
  // pass, and a strike elsewhere leaves the other dice's pairs as they were.
  // (Stamps start at 1: a fresh memo's 0 was measured at none.)
  std::array<std::uint64_t, kMaxDice> placed_at{};
  std::uint64_t stamp = 0;
  for (int k = 0; k < n; ++k) placed_at[static_cast<std::size_t>(k)] = ++stamp;
  const auto moved = [&](int k) {
    runs[static_cast<std::size_t>(k)].moved();
    placed_at[static_cast<std::size_t>(k)] = ++stamp;
  };
  // Each die's corners in the world, placed when first needed at its stamp (most pairs are settled
  // by their bounds alone).
  std::array<std::uint64_t, kMaxDice> corners_at;
  corners_at.fill(~std::uint64_t{0});
  const auto corners_of = [&](int k) {
    std::vector<Vec3>& c = corner_buf[static_cast<std::size_t>(k)];
    if (corners_at[static_cast<std::size_t>(k)] != placed_at[static_cast<std::size_t>(k)]) {
      const DieModel& d = *runs[static_cast<std::size_t>(k)].m;
      const RigidState& s = runs[static_cast<std::size_t>(k)].s;
      c.resize(d.vertices.size());
      for (std::size_t v = 0; v < c.size(); ++v) c[v] = s.position + s.R * d.vertices[v];
      corners_at[static_cast<std::size_t>(k)] = placed_at[static_cast<std::size_t>(k)];
    }
    return std::span<const Vec3>(c);
  };
  // A pair's exact touch where its bodies are now (j < 0: a piece, which never moves): the memo's,
  // if measured at these places, else measured.
  const auto touch_now = [&](PairMemo& memo, int i, int j, auto&& measure) -> const Touch& {
    const std::uint64_t at_i = placed_at[static_cast<std::size_t>(i)];
    const std::uint64_t at_j = j < 0 ? 0 : placed_at[static_cast<std::size_t>(j)];
    if (memo.measured_i != at_i || memo.measured_j != at_j) {
      memo.touch = measure();
      memo.measured_i = at_i;
      memo.measured_j = at_j;
    }
    return memo.touch;
  };
  const auto piece_touch = [&](int i, std::size_t p, PairMemo& memo) -> const Touch& {
    return touch_now(memo, i, -1,
                     [&] { return touch_piece(w, i, runs[static_cast<std::size_t>(i)].s, w.pieces[p], &memo.sep); });
  };
  const auto die_touch = [&](int i, int j, PairMemo& memo) -> const Touch& {
    return touch_now(memo, i, j, [&] {
      return touch_die(w, i, runs[static_cast<std::size_t>(i)].s, j, runs[static_cast<std::size_t>(j)].s, &memo.sep);
    });
  };

  // The start must be possible: no die inside another or inside an obstacle. (Of the polyhedra,
  // only those whose box meets the die's bounding sphere can hold it: a craps backboard's 320
  // pyramids, each measured, were a third of a craps toss.)
  for (int i = 0; i < n; ++i) {
    const RigidState& si = runs[static_cast<std::size_t>(i)].s;
    bool inside = false;
    for (const int p : w.plane_pieces)
      inside = inside || touch_piece(w, i, si, w.pieces[static_cast<std::size_t>(p)]).gap < -tol;
    w.piece_tree.visit_near(si.position, w.dice[static_cast<std::size_t>(i)].bounding_radius, 0.0, [&](int p, double) {
      inside = inside || touch_piece(w, i, si, w.pieces[static_cast<std::size_t>(p)]).gap < -tol;
    });
    for (int j = i + 1; j < n; ++j)
      inside = inside || touch_die(w, i, si, j, runs[static_cast<std::size_t>(j)].s).gap < -tol;
    if (inside) return res;  // Invalid
  }

  // Pairs whose window was a guess (dice i, j, or die i and piece p; j or p -1), and the runs at
  // the window's start to take it again from.
  struct RiskyPair {
    int i, j, p;
    double gap;  // at the window's start
  };
  constexpr int kMaxRisky = 32;
  constexpr int kMaxRetries = 24;
  std::array<RiskyPair, kMaxRisky> risky_pairs{};
  int risky_n = 0;
  // Does a risky pair (all of them, if there were more than kMaxRisky) now overlap deeper than the
  // sink, and deeper than at the window's start? Then the fraction of the window to take again
  // (1: none), from where each such pair would end in the middle of what a window may end it in:
  //  - a pair that came from a gap, half the sink deep (touching within tol, up to the sink deep):
  //    located as regula falsi from the window's start would, its gap taken as linear in time;
  //  - a pair touching at the start (a die pressed into another body by gravity), half as deep as
  //    the sink allows (no deeper than the sink, or than it started): its gap taken as falling with
  //    the square of time (from rest against the other body).
  // At most 0.9 of the window and at least 0.1.
  const auto retry_fraction = [&] {
    double fraction = 1.0;
    const auto check = [&](double gap, double start) {
      if (!(gap < -sink && gap < start)) return;
      const double ratio = start > tol ? (start + 0.5 * sink) / (start - gap)
                                       : std::sqrt(std::max(0.0, 0.5 * (start + sink) / (start - gap)));
      fraction = std::min(fraction, std::clamp(ratio, 0.1, 0.9));
    };
    // A pair's gap along its last normal is a lower bound (axis_gap): no deeper than the sink there,
    // the pair is not too deep, and GJK need not run.
    const auto piece_gap = [&](int i, std::size_t p) {
      PairMemo* memo = memos.piece(i, p);
      const ObstaclePiece& piece = w.pieces[p];
      if (!piece.plane && memo->axis.squaredNorm() > 0.0) {
        const double lower =
            axis_gap(corners_of(i), runs[static_cast<std::size_t>(i)].m->rounding, piece.corners, 0.0, memo->axis);
        if (lower >= -sink) return lower;
      }
      return piece_touch(i, p, *memo).gap;
    };
    const auto pair_gap = [&](int i, int j) {
      PairMemo* memo = memos.die(i, j);
      if (memo->axis.squaredNorm() > 0.0) {
        const double lower = axis_gap(corners_of(i), runs[static_cast<std::size_t>(i)].m->rounding, corners_of(j),
                                      runs[static_cast<std::size_t>(j)].m->rounding, memo->axis);
        if (lower >= -sink) return lower;
      }
      return die_touch(i, j, *memo).gap;
    };
    if (risky_n > kMaxRisky) {
      for (int i = 0; i < n; ++i) {
        for (std::size_t p = 0; p < w.pieces.size(); ++p) check(piece_gap(i, p), 0.0);
        for (int j = i + 1; j < n; ++j) check(pair_gap(i, j), 0.0);
      }
      return fraction;
    }
    for (int k = 0; k < risky_n; ++k) {
      const RiskyPair& q = risky_pairs[static_cast<std::size_t>(k)];
      check(q.j >= 0 ? pair_gap(q.i, q.j) : piece_gap(q.i, static_cast<std::size_t>(q.p)), q.gap);
    }
    return fraction;
  };

  double T = 0.0;
  int interactions = 0;
  // Strikes at one instant are Gauss-Seidel sweeps over the contacts there: a die wedged between
  // two bodies may have each slow strike push it into the other for ever. After kMaxSweeps at one
  // instant its slow contacts are left touching for the window (and its check), counted: a
  // multi-contact solve not converged (Corrections::pgs_unconverged, and TossProbe::sweeps_capped).
  int sweeps = 0;
  bool sweeps_capped = false;
  std::uint64_t witness_strikes = 0;
  // Touches whose contact patch came out empty, struck at the witness point alone: a fallback
  // (Corrections::fallbacks, and TossProbe::patch_witness_only).
  std::uint64_t witness_only = 0;
  std::array<double, kMaxDice> still_since;  // per die: since when it has been held still off its rest (-1: moving)
  still_since.fill(-1.0);
  // Perched: a still die held where it is by the fixed bodies it touches (obstacles, dice at rest,
  // the floor) with forces inside their friction cones (held_still: a static equilibrium), off its
  // rest on a face: leaning on a wall or on a die, lying on an obstacle's top. It waits as a die at
  // rest does (others strike it held where it lies; a fast strike wakes it, and so does any die at
  // rest woken, which it may lean on), and shows no face: once every die rests, the toss is
  // unresolved. (Unperched, each window would repeat its fall and its strikes until kStillTime
  // ended the toss so, or, jittering, it might creep out of a hold that friction keeps in fact.)
  std::array<bool, kMaxDice> perched{};
  const auto at_rest = [&](int k) {
    return runs[static_cast<std::size_t>(k)].state == RunState::Settled || perched[static_cast<std::size_t>(k)];
  };
  // Per die, the fixed bodies it was struck against slowly at this instant (ok false: a fast
  // strike, one with a moving die, or more than kMaxHolds bodies).
  struct Holds {
    bool ok = true;
    int n = 0;
    std::array<int, kMaxHolds> body{};  // the piece, or pieces.size() + the die at rest
    std::array<HeldTouch, kMaxHolds + 1> touch{};  // and the floor's, last
  };
  std::array<Holds, kMaxDice> holds{};
  const auto hold = [&](int k, int body, const Touch& t, const ContactPatch& patch, const DieModel& against) {
    Holds& h = holds[static_cast<std::size_t>(k)];
    if (!h.ok) return;
    int q = 0;
    while (q < h.n && h.body[static_cast<std::size_t>(q)] != body) ++q;
    if (q == kMaxHolds) {
      h.ok = false;
      return;
    }
    if (q == h.n) ++h.n;
    h.body[static_cast<std::size_t>(q)] = body;
    h.touch[static_cast<std::size_t>(q)] = HeldTouch{
        patch, t.normal, *std::min_element(against.vertex_friction.begin(), against.vertex_friction.end())};
  };
  const auto wake = [&](int k) {
    ImpulseRun& r = runs[static_cast<std::size_t>(k)];
    if (r.state == RunState::Settled) {  // struck at rest: it moves again from here
      r.state = RunState::Running;
      r.sustained = true;
    } else if (perched[static_cast<std::size_t>(k)]) {
      perched[static_cast<std::size_t>(k)] = false;
    } else {
      return;
    }
    r.t = T;
    r.moved();
    if (probe) ++probe->woken;
    for (int o = 0; o < n; ++o)  // dice perched on it
      if (perched[static_cast<std::size_t>(o)]) {
        perched[static_cast<std::size_t>(o)] = false;
        runs[static_cast<std::size_t>(o)].t = T;
        runs[static_cast<std::size_t>(o)].moved();
      }
  };
  std::uint64_t windows = 0;
  bool unresolved = false;
  std::array<Reach, kMaxDice> reach{};
  // Each pass visits the dice from the one that set the last window: the window it sets again
  // early, each other die's broad phase is pruned by it (a die flying toward a craps backboard
  // while the other bounces off its pyramids in short windows).
  int first = 0;

  while (!unresolved) {
    bool any_running = false;
    for (int k = 0; k < n; ++k) {
      ImpulseRun& r = runs[static_cast<std::size_t>(k)];
      reach[static_cast<std::size_t>(k)] = perched[static_cast<std::size_t>(k)] ? Reach{} : reach_of(r, probe);
      // A die that rests by the floor's rule may still rock on its face (its energy below every
      // way off it); it waits where it is, and still: the others strike a body that does not move.
      if (r.state == RunState::Settled) {
        r.s.velocity.setZero();
        r.s.omega.setZero();
      }
      any_running = any_running || (r.state == RunState::Running && !perched[static_cast<std::size_t>(k)]);
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
    int limiting = first;   // the die whose pair set the window, or was struck
    // safe(gap): the longest window the pair's bounds allow for that gap; approach(): how soon the
    // pair's corners, at their speeds now, would close it; strike(): strikes the pair if it
    // approaches (true).
    // A window longer than a pair's bound allows (nearly touching, below) is checked afterwards.
    risky_n = 0;
    const auto risky = [&](int i, int j, int p, double gap) {
      if (risky_n < kMaxRisky) risky_pairs[static_cast<std::size_t>(risky_n)] = {i, j, p, gap};
      ++risky_n;
    };
    // thick: the thinner body's least width; closing: the pair's whole-toss speed bound;
    // fly_closing: while the pair flies (0: it does not), the bound on how fast its points close
    // from the flights (their COM velocities and spins), which holds for fly_for.
    const auto consider = [&](const Touch& t, auto&& safe, auto&& approach, auto&& strike, int i, int j, int p,
                              double thick, double closing, double fly_closing, double fly_for, PairMemo& memo) {
      if (memo.at != T) memo.prev_gap = memo.gap, memo.prev_at = memo.at;
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
          // at most t_guess (t_guess_flying), and never so long that the bounds could carry one body
          // through half the other: the whole-toss bound, or while the pair flies its flights'
          // (in flight the whole-toss bound counts the height and the spin's share of the energy
          // as speed: two dice thrown together, touching now and then, crawled in windows of
          // 0.6 ms). Checked after the window (and located by retry_fraction if it went deeper
          // than the sink).
          double predicted = approach();
          if (memo.prev_at >= 0.0) {
            const double last = T - memo.prev_at;
            predicted =
                std::max(predicted, memo.prev_gap > t.gap ? t.gap * last / (memo.prev_gap - t.gap) : 2.0 * last);
          }
          double through = (t.gap + 0.5 * thick) / closing;
          if (fly_closing > 0.0) through = std::max(through, std::min((t.gap + 0.5 * thick) / fly_closing, fly_for));
          const double guess = std::min({predicted, fly_closing > 0.0 ? t_guess_flying : t_guess, through});
          if (guess > dt) {
            dt = guess;
            risky(i, j, p, t.gap);
          }
        }
        if (dt < window) window = dt, by_touch = false, limiting = i;
        memo.gap = t.gap;
        memo.at = T;
        return;
      }
      memo.at = memo.prev_at = -1.0;
      if (strike()) {
        struck = true;
        limiting = i;
      } else {
        if (touch_window < window) window = touch_window, by_touch = true, limiting = i;
        risky(i, j, p, t.gap);
      }
    };
    // Two stages: the half-spaces and the other dice first, then the polyhedra through the tree,
    // whose visits a shorter window prunes.
    for (int stage = 0; stage < 2 && !struck; ++stage)
    for (int q = 0; q < n && !struck; ++q) {
      const int i = (first + q) % n;
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
        // (The pair's memo taken only once it is needed: a far pair settled by its bound leaves the
        // memos to the pairs that use them.)
        PairMemo* memo = nullptr;
        double bound = lower;
        if (bound <= near && !piece.plane) {
          memo = memos.piece(i, p);
          // Along the pair's last normal, or (none yet) from the piece's box toward the die's centre.
          Vec3 axis = memo->axis;
          if (axis.squaredNorm() == 0.0) {
            const Vec3 c = ri.s.position;
            axis = c - c.cwiseMax(w.piece_lo[p]).cwiseMin(w.piece_hi[p]);
            if (axis.squaredNorm() > 0.0) axis.normalize();
          }
          if (axis.squaredNorm() > 0.0)
            bound = std::max(bound, axis_gap(corners_of(i), di.rounding, piece.corners, 0.0, axis));
        }
        // The window the bounds allow at gap `gap` (tt: the touch, for its normal if exact).
        const auto safe_for = [&](const Touch& tt, double gap) {
          double dt = std::max(gap / vi, sphere_dt);
          if (ai.flying) {  // gravity's part of the approach, along the piece's normal only (if known)
            // (Along a known normal the COM may be moving away faster than the spin can bring a
            // point back: the gap then grows until gravity turns it.)
            const double g_in = tt.exact ? m.gravity * tt.normal.z() : m.gravity;
            const double v_in = tt.exact ? -ai.v.dot(tt.normal) : ai.v.norm();
            const double flown = window_for(gap, v_in + ai.spin, std::max(0.0, g_in));
            dt = std::max(dt, std::min(flown, ai.free_for));
          }
          return dt;
        };
        // Even at its lower bound, a pair that allows the window as it stands is not measured
        // (a guess only lengthens a pair's window).
        if (bound > tol && safe_for(far_apart(bound), bound) >= window) return;
        if (!memo) memo = memos.piece(i, p);
        const Touch t = bound > near ? far_apart(bound) : piece_touch(i, p, *memo);
        if (t.exact) memo->axis = t.normal;
        if (t.degenerate && probe) ++probe->narrow_degenerate;
        const auto safe = [&](double gap) { return safe_for(t, gap); };
        // The other surface's plane at the touch: n . x = n . point - gap.
        const auto approach = [&] {
          return closing_time(di, corners_of(i), ri.s, t.normal, t.normal.dot(t.point) - t.gap, nullptr);
        };
        consider(t, safe, approach, [&] {
          // Every point of the patch (the witness alone may be any point of a face in contact).
          const ContactPatch patch = piece_patch(di, corners_of(i), piece, t, sink, &witness_only);
          const double un = patch_approach(patch, ri.s, nullptr, t.normal);
          if (!(un < -v_still)) {
            if (!(t.gap < -tol)) return false;
            overlap_found(ri, t.gap);  // overlapping though moving apart: lifted out, then looked at again
            ri.s.position -= t.gap * t.normal;
            moved(i);
            return true;
          }
          const bool bounce = -un > v_slow;
          if (!bounce && sweeps_capped) return false;  // left touching: checked after the window
          const DieModel& against =
              w.die_against[static_cast<std::size_t>(i)][static_cast<std::size_t>(w.piece_material[p])];
          const ImpactResult imp = strike_fixed(against, ri.s, t, patch, bounce, witness_strikes, *memo);
          ri.corrections.add(imp.corrections);
          if (bounce) holds[static_cast<std::size_t>(i)].ok = false;
          else hold(i, static_cast<int>(p), t, patch, against);
          if (t.gap < -tol) {  // found overlapping: struck, and lifted out along the normal
            overlap_found(ri, t.gap);
            ri.s.position -= t.gap * t.normal;
          }
          if (bounce) ++ri.bounces;
          ri.after_impact = false;
          ri.since_impact = 0.0;
          moved(i);
          if (probe) ++probe->interactions;
          return true;
        }, i, -1, static_cast<int>(p), std::min(w.die_width[static_cast<std::size_t>(i)], w.piece_width[p]), vi,
           ai.flying ? ai.v.norm() + m.gravity * ai.free_for + ai.spin : 0.0, ai.free_for, *memo);  // |v + g t| + spin
      };
      // Half-spaces each; the polyhedra through the tree, those whose box the bound reaches.
      if (stage == 0)
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
      if (stage == 1 && !struck)
        w.piece_tree.visit_near(ri.s.position, di.bounding_radius, reach_now(), [&](int p, double lower) {
          piece_pair(static_cast<std::size_t>(p), lower);
          return reach_now();
        });
      for (int j = 0; j < n && stage == 0 && !struck; ++j) {
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
        PairMemo* memo = nullptr;  // (as for a piece)
        double bound = far;
        if (bound <= near) {
          memo = memos.die(i, j);
          if (memo->axis.squaredNorm() > 0.0)
            bound = std::max(bound, axis_gap(corners_of(i), di.rounding, corners_of(j), rj.m->rounding, memo->axis));
        }
        const auto safe_for = [&](const Touch& tt, double gap) {
          double dt = std::max(gap / closing, sphere_dt);
          if (ai.flying && aj.flying) {  // both fly: gravity moves them alike, their relative velocity is constant
            const double v_in = tt.exact ? -(ai.v - aj.v).dot(tt.normal) : (ai.v - aj.v).norm();
            const double flown = window_for(gap, v_in + ai.spin + aj.spin, 0.0);
            dt = std::max(dt, std::min(flown, std::min(ai.free_for, aj.free_for)));
          } else if (ai.flying && vj == 0.0) {  // one flies at one at rest: as at an obstacle
            const double v_in = tt.exact ? -ai.v.dot(tt.normal) : ai.v.norm();
            const double flown =
                window_for(gap, v_in + ai.spin, std::max(0.0, tt.exact ? m.gravity * tt.normal.z() : m.gravity));
            dt = std::max(dt, std::min(flown, ai.free_for));
          }
          return dt;
        };
        if (bound > tol && safe_for(far_apart(bound), bound) >= window) continue;  // as for a piece
        if (!memo) memo = memos.die(i, j);
        const Touch t = bound > near ? far_apart(bound) : die_touch(i, j, *memo);
        if (t.exact) memo->axis = t.normal;
        if (t.degenerate && probe) ++probe->narrow_degenerate;
        const auto safe = [&](double gap) { return safe_for(t, gap); };
        const auto approach = [&] {
          // Each die's corners against the other's surface plane, relative to the other's motion
          // there. (t.point is midway between the two surfaces.)
          const double level_j = t.normal.dot(t.point) - 0.5 * t.gap;     // j's surface, seen from i
          const double level_i = -(t.normal.dot(t.point) + 0.5 * t.gap);  // i's surface, seen from j (normal -n)
          return std::min(closing_time(di, corners_of(i), ri.s, t.normal, level_j, &rj.s),
                          closing_time(*rj.m, corners_of(j), rj.s, -t.normal, level_i, &ri.s));
        };
        consider(t, safe, approach, [&] {
          // Every point of the patch (the witness alone may be any point of a face in contact).
          const ContactPatch patch = dice_patch(di, corners_of(i), *rj.m, corners_of(j), t, sink, &witness_only);
          int fastest = 0;
          const double un = patch_approach(patch, ri.s, &rj.s, t.normal, &fastest);
          // A die at rest is held by the floor: all the correction goes to the moving one.
          const double share = at_rest(j) ? 1.0 : rj.m->mass / (di.mass + rj.m->mass);
          if (!(un < -v_still)) {
            if (!(t.gap < -tol)) return false;
            overlap_found(ri, t.gap);  // overlapping though moving apart: moved apart, then looked at again
            ri.s.position -= share * t.gap * t.normal;
            rj.s.position += (1.0 - share) * t.gap * t.normal;
            moved(i);
            moved(j);
            return true;
          }
          const bool bounce = -un > v_slow;
          if (!bounce && sweeps_capped) return false;  // left touching: checked after the window
          if (!bounce && at_rest(j)) {
            // A slow contact with a die at rest: the floor's friction holds that die. (The plastic
            // push of a contact under 4 g h could slide it, at most, v^2 / (2 mu g) on its face:
            // half a millimetre at mu = 0.4.) Die i is struck against it held where it lies, at
            // every point of contact, as against an obstacle, and it stays at rest.
            const DieModel& against = w.die_against[static_cast<std::size_t>(i)][static_cast<std::size_t>(
                w.die_pair_material[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)])];
            const ImpactResult imp = strike_fixed(against, ri.s, t, patch, /*restitution=*/false, witness_strikes, *memo);
            ri.corrections.add(imp.corrections);
            hold(i, static_cast<int>(w.pieces.size()) + j, t, patch, against);
            if (t.gap < -tol) {
              overlap_found(ri, t.gap);
              ri.s.position -= t.gap * t.normal;
            }
            ri.after_impact = false;
            ri.since_impact = 0.0;
            moved(i);
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
            if (approaching) {  // (as an instant's sweeps capped, below)
              ++ri.corrections.pgs_unconverged;
              if (probe) ++probe->sweeps_capped;
            }
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
          holds[static_cast<std::size_t>(i)].ok = holds[static_cast<std::size_t>(j)].ok = false;
          for (ImpulseRun* r : {&ri, &rj}) {
            r->after_impact = false;
            r->since_impact = 0.0;
          }
          moved(i);
          moved(j);
          wake(j);
          if (probe) ++probe->interactions;
          return true;
        }, i, j, -1, std::min(w.die_width[static_cast<std::size_t>(i)], w.die_width[static_cast<std::size_t>(j)]), closing,
           ai.flying && aj.flying ? (ai.v - aj.v).norm() + ai.spin + aj.spin  // (gravity moves both alike)
           : ai.flying && vj == 0.0 ? ai.v.norm() + m.gravity * ai.free_for + ai.spin
                                    : 0.0,
           ai.flying && aj.flying ? std::min(ai.free_for, aj.free_for) : ai.free_for, *memo);
      }
    }
    first = limiting;
    if (struck) {
      if (++sweeps == kMaxSweeps) {
        sweeps_capped = true;
        ++runs[static_cast<std::size_t>(limiting)].corrections.pgs_unconverged;
        if (probe) ++probe->sweeps_capped;
      }
      if (++interactions > kMaxInteractions) unresolved = true;
      for (const ImpulseRun& r : runs)
        if (r.bounces >= r.m->max_bounces) unresolved = true;
      continue;  // gaps and bounds again from the struck state
    }

    sweeps = 0;
    sweeps_capped = false;
    // Perched: still since an earlier instant, struck at this one against fixed bodies alone, and
    // held there by them with the floor, if it touches the floor (held_still).
    for (int k = 0; k < n; ++k) {
      Holds& h = holds[static_cast<std::size_t>(k)];
      ImpulseRun& r = runs[static_cast<std::size_t>(k)];
      if (h.ok && h.n > 0 && r.state == RunState::Running && !perched[static_cast<std::size_t>(k)] &&
          still_since[static_cast<std::size_t>(k)] >= 0.0 && still(r)) {
        h.touch[static_cast<std::size_t>(h.n)] = floor_touch(*r.m, r.s, sink);
        if (held_still(*r.m, r.s, std::span(h.touch.data(), static_cast<std::size_t>(h.n) + 1), t_guess)) {
          perched[static_cast<std::size_t>(k)] = true;
          still_since[static_cast<std::size_t>(k)] = -1.0;
          r.s.velocity.setZero();
          r.s.omega.setZero();
          if (probe) ++probe->perched;
        }
      }
      h.ok = true, h.n = 0;  // (its touches are written before they are read)
    }
    // Held still: judged once this instant's strikes are done (before them, a die lying on an
    // obstacle carries what gravity gave it over the last window, which the strikes take away).
    for (int k = 0; k < n; ++k) {
      const ImpulseRun& r = runs[static_cast<std::size_t>(k)];
      double& since = still_since[static_cast<std::size_t>(k)];
      if (!(r.state == RunState::Running && !perched[static_cast<std::size_t>(k)] && still(r))) since = -1.0;
      else if (since < 0.0) since = T;
      else if (T - since > kStillTime) unresolved = true;
    }
    if (unresolved) break;

    // Advance every running die to the window's end. A window longer than its bounds allow (a
    // risky pair) is taken again shorter (retry_fraction) while such a pair ends deeper than the
    // sink bound: the contact located, as the floor's stepper locates a new corner's.
    if (risky_n > 0) saved.assign(runs.begin(), runs.end());
    for (int tries = 0;; ++tries) {
      const double t_end = std::min(T + window, m.max_time);
      ++windows;
      for (int k = 0; k < n; ++k) {
        ImpulseRun& r = runs[static_cast<std::size_t>(k)];
        if (r.state != RunState::Running || perched[static_cast<std::size_t>(k)]) continue;
        r.advance(t_end, probe);
        placed_at[static_cast<std::size_t>(k)] = ++stamp;
      }
      double again = risky_n == 0 ? 1.0 : retry_fraction();
      if (again < 1.0 && tries == kMaxRetries) {  // taken as it is: its overlap is lifted out next, counted if deep
        again = 1.0;
        if (probe) ++probe->retries_capped;
      }
      if (again >= 1.0) {
        // A touching pair's window doubles while whole windows pass; once one had to be taken
        // again, it grows by a quarter (doubling, every other window would be taken again).
        if (by_touch && tries == 0) touch_window = std::min(t_guess, touch_growth * touch_window);
        else if (by_touch) touch_window = window, touch_growth = 1.25;
        else touch_growth = 2.0;
        T = t_end;
        break;
      }
      std::copy(saved.begin(), saved.end(), runs.begin());
      for (int k = 0; k < n; ++k) placed_at[static_cast<std::size_t>(k)] = ++stamp;
      window *= again;
      if (probe) ++probe->windows_halved;
    }
    for (const ImpulseRun& r : runs)
      if (r.state == RunState::Unresolved) unresolved = true;
  }
  if (probe) {
    probe->windows += windows;
    probe->witness_strikes += witness_strikes;
    probe->patch_witness_only += witness_only;
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
  res.corrections.fallbacks += static_cast<std::uint32_t>(witness_only);
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

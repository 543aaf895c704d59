// Fixed-step time integration of the die with the floor: gravity, exact torque-free rotation
// (sim/torque_free.hpp) and straight COM motion between the step's impulses, and at every step
// the corners touching the floor solved together with Coulomb friction (sim/friction_impact.hpp):
// first an impact with restitution if a corner arrives faster than the impact threshold, then,
// with the step's gravity applied, the perfectly plastic contact solve that supports the die
// (resting, sliding, rolling, tipping). Semi-implicit Euler, first order: the answer converges as
// h -> 0. A corner that would reach the floor inside a step is not pushed back out of it: the step
// is shortened to the instant it touches (located by a root search on the step's free motion), so
// its impact is solved where and when it happens. The whole of the `stepped` fidelity, and
// `impulse`'s sustained-contact phases.
//
// Energy: no step gains mechanical energy E = kinetic + m g z_com (the rotation is exact, a step
// without contact loses m g^2 h^2 / 2, the plastic solve after gravity's kick loses at least
// (F - m g h)^2 / 2m with F its normal impulse, and no impact gains). `max_energy_gain` records
// the largest relative gain seen, for the tests. (A curved die's steps are drift-kick-drift, second
// order, their support solve at the step's middle: rim_step.cpp. Such a step may gain up to
// m (g h)^2 / 8, split_gain; checked, and capped beyond it.)
#pragma once

#include <limits>
#include <optional>

#include "sim/body/die_model.hpp"
#include "sim/dynamics/corrections.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/dynamics/friction_impact.hpp"

namespace dicesim {

// Which approach speed makes a step's contact an impact (restitution, counted against
// sim.max_bounces) rather than sustained contact (plastic, not counted).
//  Gravity: 4 g h, what gravity alone adds in a step (`impulse`'s sustained contact).
//  Contact: h (4 g + (1 + mu_max) g m r^2 / I_min + 4 |w|^2 r), r the bounding radius: a bound on
//   a corner's approach built up in one step of sustained contact, from gravity, from the angular
//   acceleration that contact forces of order m g (normal plus friction) give at lever r, and
//   from the spin's centripetal term. Under the gravity threshold a die sliding flat on a face
//   rocks from corner to corner (friction pitches it; one corner touches per step), its corners
//   arriving at ~6-8 g h, and a fast-spinning contact corner drifts in by ~w^2 r h per step:
//   every step was a counted, bouncing impact, so the count grew like 1/h and fine steps hit
//   sim.max_bounces. Both thresholds vanish with h (a genuine impact arrives at a speed that
//   does not), so the limit h -> 0 is the same physics.
enum class ImpactThreshold { Gravity, Contact };

// The approach speed below which `impulse` hands a contact to the stepper (sustained contact),
// and below which the stepper (Gravity threshold) treats a contact as plastic: 4 g h. Faster
// contacts are impacts, solved exactly at their instant.
inline double sustained_contact_speed(const DieModel& m, double h) { return 4.0 * m.gravity * h; }

// `impulse`'s bound on how far a held corner of a flat-faced die may end a step below the floor
// (m). Over a step the touching corners move with the die's free rotation after the support
// solve, and a corner whose centripetal and Euler acceleration points down, a_n < 0, ends it
// a_n d^2 / 2 deep (the solve stops its approach at the start only). The step is shortened until
// that depth is within this bound (FixedStepper's max_sink): 1e-4 of the bounding radius.
inline double held_corner_sink(const DieModel& m) { return 1e-4 * m.bounding_radius; }

// `impulse`'s sustained phase (tol > 0): leapfrog steps whose length an error estimate chooses,
// drift-kick-drift: the free motion for half the step, gravity's whole kick and the support solve
// at the step's middle, the free motion for the other half (try_step_dkd). Every step starts and
// ends with a true velocity, so its length may change from one step to the next, and a step's
// energy obeys the fixed step's argument with the solve at the middle (docs/fidelity.md "Energy in
// sustained contact"). (Kick-drift-kick with the support solve at the start, tried first, gains
// m_eff (g h)^2 / 8 whenever a corner the solve held lifts off within the step: the opening
// half kick's impulse lifts the COM through the whole step, and nothing resists the closing half.)
// After each step, the contact's mean force and torque over it are compared with the previous
// step's; the change, times (h^2 / 2) / m and (h^2 / 2) r / I_min, is the position error of a body
// point that a step of length h makes where the contact force changes (a corner lifting, sliding
// turning to sticking): the next step is the length at which that estimate is tol r, within
// [floor, h] and at most double the last (a quarter at least).
// tol = 0: fixed steps of h (first order), as `stepped`.
// The impact threshold is then 4 g threshold_step, a fixed speed (the shape's default contact step,
// DieModel::sustained_step), not 4 g h: the ceiling h may change without changing the physics.
struct AdaptiveSteps {
  double tol = 0.0;             // relative to the bounding radius (sim.contact_tol)
  double floor = 0.0;           // the shortest step the estimate may ask for (s; located steps may be shorter)
  double threshold_step = 0.0;  // s; 0: h
};

class FixedStepper {
 public:
  // max_sink > 0 (a flat-faced die only): each step with contact is shortened from h, down to
  // h / kMinStepDivisor at most, until its held corners end it no deeper than max_sink below the
  // floor: predicted from their acceleration at the start, checked on the accepted step (and the
  // step tried again shorter if deeper). 0: every step is h (the thresholds use h either way).
  FixedStepper(const DieModel& m, double h, ImpactThreshold threshold = ImpactThreshold::Gravity,
               double max_sink = 0.0, const AdaptiveSteps& adaptive = {});
  static constexpr double kMinStepDivisor = 8.0;

  // Advances s by one step: h (or the step max_sink allows), or less if a new corner reaches the
  // floor first (last_dt()).
  // Returns the number of corners that were in contact at the step's start.
  int step(RigidState& s);
  // The same given ke = kinetic_energy(m, s) (contact.hpp); end_ke() is then the kinetic energy of
  // s as the step leaves it (a curved die's lift at the end moves only its position): the stepper's
  // loop hands it to the rest check and to the next step instead of computing it again.
  int step(RigidState& s, double ke);
  double end_ke() const { return end_ke_; }

  // `stepped`'s flights in closed form: from s, with the COM at least the bounding radius above
  // the floor, the number K <= max_k of whole steps (each h) after which every step's start and
  // end would still be that high, and s advanced by them at once. Such steps touch nothing, give
  // no impulse and cannot end in rest (the COM is above every basin's escape height); each is the
  // same map (gravity's kick g h, then straight COM motion and the exact torque-free rotation for
  // h), so K of them are v_K = v - K g h, p_K = p + K h v - g h^2 K (K + 1) / 2 e_z, and the
  // rotation for K h from the one angular momentum (constant in flight). The same discrete motion
  // as K calls of step(), to rounding. t advances by K additions of h, as the steps add it, and K
  // stops where t reaches max_time (the steps' own time cap). Returns K (0: s, t unchanged).
  long long coast(RigidState& s, double& t, double max_time, long long max_k) const;

  double h() const { return h_max_; }
  // Adaptive steps: the length the next step will have (before location or max_sink).
  double next_step() const { return h_ctrl_; }
  double last_dt() const { return dt_; }
  int impacts = 0;                // steps whose contact solve had restitution
  Corrections corrections;        // of every solve and step so far
  std::uint64_t sweeps = 0;       // Gauss-Seidel sweeps of every solve so far
  std::uint64_t located = 0;      // steps shortened to a new contact's instant
  std::uint64_t located_trials = 0;  // whole trial steps of those shortened steps (the full one not counted)
  // ... of them not within the touch tolerance in kMaxTrials trials (a nearly tangential touch):
  // the longest trial that ends above the floor taken, the corner touching in the next step.
  std::uint64_t located_capped = 0;
  double max_energy_gain = 0.0;   // largest relative gain of one impact's kinetic or one step's mechanical energy
  // Plain E = kinetic + m g z_COM over one accepted step (before any counted lift), docs/fidelity.md
  // "Energy": its largest rise as a height, (E_end - E_start) / (m g) (m), and the largest relative
  // excess of E_end over E_start + m g (the deepest held corner's depth at the step's start).
  double max_step_rise = 0.0;
  double max_rise_excess = 0.0;
  double max_penetration = 0.0;   // curved dice: deepest lowest point below the floor at a step's end (m)
  std::uint64_t curvature_capped = 0;    // curved dice: support solves at a step's middle capped to gain no energy (any trial)
  // Curved dice: support searches (mid_support's push or eased push) out of iterations, their
  // bracket's end above the floor taken (the rim ends a little above it); any trial.
  std::uint64_t support_search_capped = 0;
  std::uint64_t halved = 0;              // curved dice: steps halved because the cap left them sinking
  std::uint64_t slaps = 0;               // curved dice: steps shortened to a slapping face's arrival
  // Curved dice: the slap's two re-decisions (step()): the plain step taken because a slap's far
  // half does not reach the floor within the full step, and the plain step's search run again
  // because a located slap step left the rest of the rim below the floor.
  std::uint64_t slap_no_arrival = 0;
  std::uint64_t slap_rim_below = 0;
  // Curved dice: steps still capped after the halvings or ending with the rim below the floor,
  // taken again from their start with the face's tripod struck because it reaches the floor
  // within the step or lies that close (step(): a coin landing or lying nearly flat).
  std::uint64_t flat_landed = 0;
  // Curved dice: of those, the steps whose support gained by its own work after the
  // halvings (kind B, issue 13: a near-flat coin's lowest point jumping across the face) and whose
  // face arrives within the step at one tripod point (the other may be rising).
  std::uint64_t face_jumped = 0;
  std::uint64_t face_jump_declined = 0;  // ... taken again but not kept (it clamped or lifted again)
  // Curved dice: steps still capped after the halvings (or ending below the floor) whose impact
  // struck the face's tripod while an arc of the rim between its points still came down, taken
  // again with that arc struck too (step(), strike_rim); and those not kept.
  std::uint64_t rim_struck = 0;
  std::uint64_t rim_strike_declined = 0;
  // Impacts whose restitution friction was taken by the dual solve (Gauss-Seidel stalled).
  std::uint64_t dual_solves = 0;
  // Solves of accepted steps (impacts and supports) that an exact second method took
  // (ImpactResult::exact_fallbacks).
  std::uint64_t exact_fallbacks = 0;
  double max_held_sink = 0.0;            // flat dice: deepest held corner below the floor at a step's end (m)
  std::uint64_t held_sinks = 0;          // flat dice: steps in which a held corner sank more than max_sink (or touch_tol)
  std::uint64_t sink_shortened = 0;      // flat dice, max_sink: steps tried again shorter (deeper than max_sink)
  std::uint64_t short_steps = 0;         // flat dice, max_sink: steps whose full length was below h
  std::uint64_t rise_dropped = 0;        // flat dice, max_sink: steps whose held corners' rise would gain energy (plain)

 private:
  // Adaptive: the next step's length from this step's mean contact force and torque against the
  // last step's (AdaptiveSteps). s0: the step's start after its impact.
  void adapt(const RigidState& s0, const RigidState& s, double dt);
  bool leapfrog() const { return adaptive_.tol > 0.0; }  // drift-kick-drift (try_step_dkd)
  // The most a leapfrog step of length d may raise E = kinetic + m g z_COM (docs/fidelity.md
  // "Energy in sustained contact"): m (g d)^2 / 8, reached where a held corner leaves the floor at
  // half the kick's speed at the step's middle. 0 for fixed steps (their solve after the whole kick
  // never gains).
  double split_gain(double d) const {
    return leapfrog() || m_->curved() ? 0.125 * m_->mass * (m_->gravity * d) * (m_->gravity * d) : 0.0;
  }
  // The longest step (<= h_max_) whose held corners, moving with the die's free rotation from the
  // step's start, sink no more than max_sink_ below the floor within it (to second order in d;
  // what try_step's rise does not hold); sets a_down_.
  double predicted_step(const RigidState& s0, const ContactSet& c);
  // A flat die's corners of c from the step's start s0 to its end s: the most any of them sank
  // (its depth at the end less its depth at the start, if it started below the floor) and, in
  // depth, the deepest one's depth at the end (> 0: below the floor).
  double held_sink(const RigidState& s0, const RigidState& s, const ContactSet& c, double& depth) const;
  // The rest rules' energy of s (rest.hpp): kinetic + m g (COM height + the deepest corner of c's
  // depth below the floor, if any).
  double held_energy(const RigidState& s, const ContactSet& c) const;
  // One trial step of length d from s0 with contact set c; full: the step of length h, whose
  // free motion is kept (full_*) as the model of the shortened steps.
  struct Attempt {
    RigidState s;
    bool impact = false;
    ImpactResult imp, sup;
    ContactImpulses next;
    double G = 0.0;  // lowest height at the step's end over corners not in c
    bool capped = false;  // curved: the middle's support was capped and left the rims below the floor
    bool clamped = false; // curved: the middle's support was capped (to gain no energy) at all
    bool to_halve() const { return capped; }  // step() halves it (halve_while_capped)
    bool risen = false;   // flat: the held corners were asked to rise (try_step); else the plain solve
    bool rise_dropped = false;  // flat: they could not be without gaining energy (the plain solve instead)
    double held_e = 0.0;  // risen: held_energy of s (its check in try_step_with)
    // curved, one rim point in c: its slip after the middle's solve (the next step reflects the
    // change from it, mid_support), and which feature it was (-1: none)
    Eigen::Vector2d slip = Eigen::Vector2d::Zero();
    int slip_vertex = -1;
  };
  void try_step(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full = false);
  // try_step_with's leapfrog step from a.s = s0 (a flat die): the free motion for d / 2 (start_rot_), the
  // kick g d and the support solve (held corners asked to rise at bias) there, the free motion of
  // the result for d / 2. full: also the location model's free motion (model_G: from s0 with the
  // solve's velocities, an approximation the trials correct). Sets a.G at the end.
  void try_step_dkd(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full, double bias);
  // A curved die lying flat to within the strike tolerance: its face's tripod added to c (also
  // when each tripod point lies within `depth` or reaches the floor within `window`: step()).
  // either: one tripod point joining suffices (both are added; step()'s kind B re-decision).
  void add_face_tripod(const RigidState& s, ContactSet& c, double window = 0.0, double depth = 0.0,
                       bool either = false) const;
  // A curved die whose face's tripod (features 3r, 3r+1, 3r+2 of rim r all in c) is struck: the
  // rim's most approaching point in the motion of s (the minimum over the circle of its normal
  // velocity, in closed form), its lever arm and normal velocity; false if no such rim, or if
  // that point neither lies within the strike tolerance of the floor nor reaches it within
  // `window` at its speed.
  bool rim_most_approaching(const RigidState& s, const ContactSet& c, double window, int& rim, Vec3& r,
                            double& vz) const;
  // The step's impact at c's points plus the rims' most approaching points, added one at a time
  // while the impact leaves one approaching (step()'s rim strike).
  ImpactResult strike_rim(RigidState& s0, const ContactSet& c);
  // try_step with the held corners asked to rise at `bias` (m/s, 0: none); false if that gains
  // energy (kinetic + m g (COM height + the deepest corner's depth), plus split_gain). Sets a to
  // s0 and the step's impact with its flags cleared, then takes the step below that fits.
  bool try_step_with(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full, double bias);
  // Its fixed (first-order) step from a.s = s0: the kick g d and the support solve there, then the
  // free motion for d.
  void try_step_fixed(const RigidState& s0, const ContactSet& c, double d, Attempt& a, bool full, double bias);
  // A curved die's step of length d from a.s (its start, after the impact), drift-kick-drift
  // (rim_step.cpp): a plastic impulse for a point of c that arrives approaching, the free motion
  // for d / 2, gravity's whole kick and the support solve there (rim_support), the free motion
  // of the result for d / 2. Sets a.G at the end. full: the step of length h.
  void try_step_rim(const ContactSet& c, double d, Attempt& a, bool full);
  // The support solve at the step's middle, s (the kick in it), for the d left of the step
  // (mid_support), then, for the full step, whether the sinking is another part of the rim
  // arriving (rims_new_). Leaves s and rot such that rot's free motion of s for d is the rest of
  // the step. geo: the contact set-up at s.R.
  void rim_support(RigidState& s, const ContactSet& c, double d, Attempt& a, std::optional<TorqueFreeRotation>& rot,
                   bool full, ContactGeometry& geo);
  // Plastic, with the rims' resistances; asked to leave the touching rims' lowest points on the
  // floor at the end, a single point's slip reflected; no gain beyond split_gain (rim_step.cpp).
  void mid_support(RigidState& s, const ContactSet& c, double d, Attempt& a, std::optional<TorqueFreeRotation>& rot,
                   ContactGeometry& geo);
  // The model of G(d) from the full step's free motion: its lowest new corner at t, raised by what
  // the smaller gravity kick of a step of length t changes, g (h - t) t. Exact for a step without
  // contact (the rotation is the same); with contact the solve absorbs part of the kick.
  double model_G(const ContactSet& c, double t) const {
    double slope;
    return lowest_new(c, full_p_, full_v_, *full_rot_, t) + model_kick(t, slope);
  }
  // model_G's term for the kick, and its slope in t: fixed steps g (h - t) t (the kick g t comes
  // before the motion); leapfrog g (2 h - t) t / 2 (a step of length t kicks at t / 2: exact
  // without contact) + model_slope_ t.
  double model_kick(double t, double& slope) const {
    if (!leapfrog()) {
      slope = kick_g_ * (h_ - 2.0 * t);
      return kick_g_ * (h_ - t) * t;
    }
    slope = kick_g_ * (h_ - t) + model_slope_;
    return 0.5 * kick_g_ * (2.0 * h_ - t) * t + model_slope_ * t;
  }
  // Leapfrog: what makes model_G exact at the full step too (its G less the model's there, / h; the
  // model is of a kick before the motion, the step's kick is at its middle). 0: fixed steps.
  double model_slope_ = 0.0;
  // The model corrected by a trial's miss: model_G(t) + (miss + miss_rate_ t) t (h - t) (the model
  // is exact at t = 0, the step's start, and at t = h, the full step itself; miss_rate_, 0 unless
  // predicted_miss set it, the miss's first-order change as the arriving corner turns).
  double corrected(double model_g, double miss, double t) const {
    return model_g + (miss + miss_rate_ * t) * t * (h_ - t);
  }
  // A flat die's prediction of the miss (the corrected model's coefficient) before any shortened
  // trial: the support solve linearised in the step length at the full step (contact_location.cpp).
  // Sets miss_rate_. r: the arriving corner's lever at the step's start.
  double predicted_miss(const ContactSet& c, const Vec3& r);
  // A flat die's starting point for model_root: the root in (lo, hi) of the corrected model with
  // the arriving corner's rotation replaced by a cubic (contact_location.cpp); x if none is found.
  double hermite_start(double miss, double lo, double hi, double x) const;
  // The root of the corrected model in [lo, hi], given its values f_lo > 0 at lo and f_hi <= 0 at
  // hi: a flat die's by Newton on the model (its slope from the rotation's rate), safeguarded by
  // the bracket; a curved die's by Illinois. g_model: in, model_G(hi); out, model_G at the
  // returned point.
  double model_root(const ContactSet& c, double miss, double lo, double hi, double f_lo, double f_hi,
                    double& g_model) const;
  // A curved die's lowest height relative to the COM over what counts as a new contact at
  // orientation R: the features not in c, or the whole rim (rims_new_), or, in a slap, the far
  // half of the slapping rim (slap_low).
  double curved_low(const ContactSet& c, const Mat3& R) const;
  // The lowest point, relative to the COM, of the half of rim `rim` whose body directions make
  // more than 90 deg with slap_u_[rim] (the rim's lowest point at the slap's start), in closed form.
  // rim < 0: the near half of rim -rim - 1 instead.
  double slap_low(const Vec3& z_row, int rim) const;
  // The touching rim's lowest point the middle's support holds: the whole rim, or in a slap the
  // near half (the far half is the arriving part).
  double support_low(const Vec3& z_row, int rim) const;
  // The lowest height over corners not in c, at time t of the free motion after the step's solve.
  double lowest_new(const ContactSet& c, const Vec3& p, const Vec3& v, const TorqueFreeRotation& rot, double t) const;
  // The same for a flat-faced die, given the orientation's bottom row at t.
  double lowest_flat(const ContactSet& c, const Vec3& p, const Vec3& v, const Vec3& z_row, double t) const;
  // lowest_flat with its slope in t (the lowest corner's height rate; z_rate: the row's rate).
  double lowest_flat(const ContactSet& c, const Vec3& p, const Vec3& v, const Vec3& z_row, const Vec3& z_rate,
                     double t, double& slope) const;
  const DieModel* m_;
  TorqueFreeRotation::Moments moments_;  // the die's, for its many rotations' set-ups
  // The vertices by coordinate, for lowest_flat's vectorised pass (flat dice of up to
  // kSoaVertices corners; soa_vertices_ = 0: the plain loop).
  static constexpr int kSoaVertices = 64;
  int soa_vertices_ = 0;
  // (An odd count is padded with the last vertex again, for the two-at-a-time pass.)
  alignas(16) double vx_[kSoaVertices], vy_[kSoaVertices], vz_[kSoaVertices];
  // The heights relative to the COM of every vertex for the bottom row z_row (the same products
  // and sums, in the same order, as z_row.dot(vertex)) into z (padded as vx_), the contact set's
  // corners as +inf; returns their minimum (+inf if every corner is in c).
  double soa_heights(const ContactSet& c, const Vec3& z_row, double* z) const;
  // touching_corners(m, s, touch_tol_) from the same arrays, two corners at a time: the same
  // heights (corner_height's (p_z + (R20 x + (R21 y + R22 z))) - rounding), the same set in
  // ascending order, into c (as a fresh ContactSet). False if more than kMaxContacts touch (c
  // then partly filled: the caller takes touching_corners).
  bool soa_touching(const RigidState& s, ContactSet& c) const;
  double h_max_;  // the contact step h (thresholds, coast; adaptive: the ceiling)
  AdaptiveSteps adaptive_;
  double h_ctrl_;            // adaptive: the next step's length from the error estimate (else h_max_)
  double kick_g_;            // the kick per unit step length before a step's solve: g
  bool have_force_ = false;  // adaptive: force_/torque_ hold the last step's mean contact force
  Vec3 force_ = Vec3::Zero(), torque_ = Vec3::Zero();
  double h_;      // the current step's full length (h_max_, or shorter for max_sink_)
  double v_impact_, touch_tol_;
  double max_sink_ = 0.0;
  // The current step's held corners (max_sink_ > 0, try_step): whether they are held to the floor
  // at its end, the deepest and the shallowest one's depth below the floor at its start (m, >= 0),
  // and their most downward acceleration in the free rotation (m/s^2, >= 0; predicted_step).
  bool hold_ = false;
  double start_depth_max_ = 0.0;
  double start_shallow_ = 0.0;
  double a_down_ = 0.0;
  double v_spin_ = 0.0;  // Contact: 4 h r, the factor of |w|^2 in the threshold
  // The normal speed above which a contact point's approach in state s is an impact.
  double impact_speed(const RigidState& s) const { return v_impact_ + v_spin_ * s.omega.squaredNorm(); }
  double dt_ = 0.0;
  double end_ke_ = 0.0;  // step(): the kinetic energy of the state it returns
  Mat3 rot_start_ = Mat3::Identity();  // orientation at the start of the step being tried
  Mat3 Iw_start_ = Mat3::Identity();   // its world inertia (every trial's angular momentum)
  Eigen::Vector2d rim_slip_ = Eigen::Vector2d::Zero();  // the accepted step's Attempt::slip
  int rim_slip_vertex_ = -1;                              // ... and slip_vertex
  double e_start_ = 0.0;                // its mechanical energy after the impact (the trials' checks)
  Attempt a_, b_, lo_;                  // trial steps (members: ContactImpulses is large)
  ContactImpulses warm_;  // the last plastic solve's impulses (warm start of the next)
  ContactGeometry geo_;   // the contact set-up of the current step (shared by its solves)
  std::optional<TorqueFreeRotation> full_rot_;   // the full step's free motion (model_G)
  std::optional<TorqueFreeRotation> trial_rot_;  // a shortened trial's
  std::optional<TorqueFreeRotation> start_rot_;  // leapfrog: the step's start's free motion (every trial's first half)
  Vec3 full_p_ = Vec3::Zero(), full_v_ = Vec3::Zero();
  Vec3 full_w_ = Vec3::Zero();
  double miss_rate_ = 0.0;
  // The held corners' rise the full step's solve was asked for (m/s: b, b / 4 or 0, try_step):
  // with no depth at the start it is linear in the step length, and the shortened steps' solves
  // see the kick g d plus it (predicted_miss).
  double full_bias_ = 0.0;
  // Leapfrog: the held corners' tangential velocity at the step's middle (leapfrog_bias, the
  // tangential part of the bias; try_step sets it for try_step_dkd's solve).
  Eigen::Vector2d slip_bias_ = Eigen::Vector2d::Zero();
  // Leapfrog: a horizontal spin (rad/s, world) added to the solve's target with slip_bias_ and the
  // normal bias, so that each held corner is asked for its own rise (leapfrog_bias).
  Vec3 tilt_bias_ = Vec3::Zero();
  // Leapfrog: start_rot_'s state at mid_d_ / 2 (the bias's, try_step), reused by try_step_dkd's
  // first half drift of the same trial; mid_d_ < 0: none.
  Mat3 mid_R_ = Mat3::Identity();
  Vec3 mid_w_ = Vec3::Zero();
  double mid_d_ = -1.0;
  bool hermite_ = false;  // hq_ holds the arriving corner's height and rate at t = 0 and h
  double hq_[4] = {0.0, 0.0, 0.0, 0.0};  // the corrected model's miss grows by this per unit t (predicted_miss)  // the full step's angular velocity after its support solve
  // A curved die whose touching rims the support solve does not push (their material points leave
  // the floor) while the rims' lowest points end the full step below it: another part of the rim
  // is coming down (a near-flat coin whose lowest point runs along the rim, a slap). The rims'
  // lowest points then count as new contacts (lowest_new), so the step is shortened to the
  // instant that part touches, and the next step strikes it. Not twice running (slap_located_):
  // a rim whose lowest point sinks from the start would be located again at once.
  bool rims_new_ = false;
  bool slap_located_ = false;  // the last step was shortened to such an arrival
  // A near-flat coin's face slapping down (pivoting on one rim point about a near-horizontal axis):
  // the touching rim's lowest point turns by more than 90 deg along the rim within the step (its
  // tilt passes through or near zero). Then the far half of that rim is the arriving part
  // (slap_low): the step is shortened to the instant it reaches the floor and the next step
  // strikes it (an impact, as a polyhedron's face landing). slap_rims_: bit r for rim r; slap_u_:
  // each one's lowest direction at the step's start in the rim's body basis (perp, axis x perp).
  // A slap located step whose whole rim still ends below the floor (the lowest point ran round the
  // rim on the near half first) is dropped for the plain step.
  int slap_rims_ = 0;
  // Set (window = the full step, > 0) when step() takes a step again with the face's tripod struck
  // (a coin landing or lying nearly flat): its next call widens add_face_tripod by these, once.
  double land_window_ = 0.0, land_depth_ = 0.0;
  bool land_either_ = false;  // ... with one tripod point arriving enough (a kind B step)
  // Set when step() takes a step again with its impact struck at the rim's most approaching
  // points as well (strike_rim): read and cleared by its next call.
  bool rim_strike_ = false;
  Vec3 free_end_row_ = Vec3::Zero();  // the full step's bottom row at its end, after the start's solve only
  double slap_u_[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
  bool impact_ = false;   // the current step starts with an impact (solved once for all its trials)
  ImpactResult imp_;      // that impact's result
};

// Paused: the time t_pause reached (a world toss's window: run_fixed_steps).
enum class StepperExit { Settled, LiftOff, Unresolved, Paused };

struct StepperOutcome {
  StepperExit exit = StepperExit::Unresolved;
  int face_down = -1;  // Settled: face index on the floor
  int nudges = 0;      // exact balances broken by the toss's tiebreak
};

// Stepper statistics handed back to the toss.
// Watches the sustained phase without changing it (`dicesim show`'s trace of a toss): called with
// the time and the state after every accepted step (a coast counts as one), and once more at the
// phase's end with the state it hands back (the same time as its last step).
class StepObserver {
 public:
  virtual void on_step(double t, const RigidState& s) = 0;

 protected:
  ~StepObserver() = default;
};

struct StepperStats {
  StepObserver* observer = nullptr;  // optional; not a statistic (read, never accumulated)
  Corrections corrections;
  std::uint64_t sweeps = 0;
  std::uint64_t steps = 0;
  std::uint64_t located = 0;  // steps shortened to a new contact's instant
  std::uint64_t located_trials = 0;  // their trial steps of shortened length
  std::uint64_t located_capped = 0;  // ... not within the tolerance in kMaxTrials trials (FixedStepper)
  std::uint64_t nudges = 0;          // exact balances at rest broken by the toss's tiebreak (a tiny spin)
  double max_energy_gain = 0.0;
  double max_step_rise = 0.0;    // FixedStepper::max_step_rise (m)
  double max_rise_excess = 0.0;  // FixedStepper::max_rise_excess (relative)
  double max_penetration = 0.0;  // curved dice: deepest lowest point below the floor at a step's end (m)
  // Curved dice, adaptive steps (not corrections): steps halved because a capped support left the
  // rims sinking, supports at a step's middle capped (in any trial), steps shortened to a slap.
  std::uint64_t halved = 0;
  std::uint64_t curvature_capped = 0;
  std::uint64_t support_search_capped = 0;  // support searches out of iterations, the end above the floor taken
  std::uint64_t slaps = 0;
  std::uint64_t slap_no_arrival = 0;  // a slap's far half did not arrive: the plain step taken
  std::uint64_t slap_rim_below = 0;   // a located slap left the rest of the rim below: the plain search again
  std::uint64_t flat_landed = 0;      // steps taken again with a nearly flat face's tripod struck
  std::uint64_t face_jumped = 0;      // ... of them kind B steps (a near-flat coin's lowest point jumping)
  std::uint64_t face_jump_declined = 0;  // kind B steps taken again with the face struck, not kept
  std::uint64_t rim_struck = 0;          // tripod impacts taken again with the rim's approaching arc struck
  std::uint64_t rim_strike_declined = 0;  // ... taken again but not kept
  std::uint64_t dual_solves = 0;      // impacts whose restitution friction the dual solve took
  std::uint64_t exact_fallbacks = 0;  // accepted steps' solves an exact second method took (ImpactResult)
  // Flat dice (not corrections: a step's discretisation, reported): the deepest held corner below
  // the floor at a step's end, the steps that ended deeper than the max_sink bound, and with
  // max_sink the steps tried again shorter and those whose full length was below h.
  double max_held_sink = 0.0;
  std::uint64_t held_sinks = 0;
  std::uint64_t sink_shortened = 0;
  std::uint64_t short_steps = 0;
  std::uint64_t rise_dropped = 0;  // `impulse`: steps whose held corners' rise was dropped (it would gain energy)
};

// No pause: run_fixed_steps steps on to rest, lift-off or a cap.
inline constexpr double kNoPause = std::numeric_limits<double>::infinity();
// A pause this close (in steps) counts as reached: rounding of t's sum never leaves a sliver step.
inline constexpr double kPauseSlack = 1e-9;

// Steps from (s, t) until the die must come to rest (sim/rest.hpp), the time cap, the impact cap
// (`impacts` counts on), or, with allow_liftoff, until no corner touches or will touch within two
// steps (the caller's exact flight takes over). A die at rest in an exact unstable balance (on an
// edge or corner) gets an infinitesimal spin whose direction comes from `tiebreak`. `stats`, if
// given, accumulates the corrections, sweeps and energy check of the steps.
// adaptive.tol > 0: `impulse`'s leapfrog steps of error-controlled length, h their ceiling.
// t_pause: a world toss's window end (world_toss.cpp): the last step is shortened to end there,
// and the stepper returns Paused with t == t_pause (to kPauseSlack steps).
StepperOutcome run_fixed_steps(const DieModel& m, RigidState& s, double& t, int& impacts, double h, double tiebreak,
                               bool allow_liftoff, ImpactThreshold threshold = ImpactThreshold::Gravity,
                               StepperStats* stats = nullptr, double max_sink = 0.0, const AdaptiveSteps& adaptive = {},
                               double t_pause = kNoPause);

}  // namespace dicesim

// The die and one toss as the viewer's JSON (show_data.hpp).
#include "web/show_data.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "sim/body/outcome.hpp"
#include "sim/dynamics/contact_stepper.hpp"
#include "sim/dynamics/flight.hpp"
#include "sim/dynamics/friction_impact.hpp"
#include "sim/models/initial_state.hpp"
#include "sim/models/toss.hpp"

namespace dicesim::web {
namespace {

using nlohmann::json;
using Polygon = std::vector<Vec3>;

// Rounded to ~7 significant digits: the page needs no more, and the file stays small.
double r7(double x) {
  if (x == 0.0 || !std::isfinite(x)) return 0.0;
  const double scale = std::pow(10.0, 6 - static_cast<int>(std::floor(std::log10(std::abs(x)))));
  return std::round(x * scale) / scale;
}
json vec(const Vec3& v) { return json::array({r7(v.x()), r7(v.y()), r7(v.z())}); }

// The convex solid `faces` cut by {x : n.x <= d}: each face clipped, plus the cap in the plane.
std::vector<Polygon> clip(const std::vector<Polygon>& faces, const Vec3& n, double d, double eps) {
  std::vector<Polygon> out;
  std::vector<Vec3> cap;
  for (const Polygon& f : faces) {
    Polygon p;
    for (std::size_t i = 0; i < f.size(); ++i) {
      const Vec3& a = f[i];
      const Vec3& b = f[(i + 1) % f.size()];
      const double da = n.dot(a) - d, db = n.dot(b) - d;
      if (da <= eps) p.push_back(a);
      if (std::abs(da) <= eps) cap.push_back(a);
      if ((da < -eps && db > eps) || (da > eps && db < -eps)) {
        const Vec3 x = a + (b - a) * (da / (da - db));
        p.push_back(x);
        cap.push_back(x);
      }
    }
    if (p.size() >= 3) out.push_back(std::move(p));
  }
  // The cap: the points in the plane, ordered counter-clockwise seen from outside (along +n).
  Polygon unique;
  for (const Vec3& c : cap)
    if (std::none_of(unique.begin(), unique.end(), [&](const Vec3& u) { return (u - c).norm() <= 10 * eps; })) unique.push_back(c);
  if (unique.size() >= 3) {
    Vec3 centre = Vec3::Zero();
    for (const Vec3& u : unique) centre += u;
    centre /= static_cast<double>(unique.size());
    const Vec3 nn = n.normalized();
    const Vec3 e1 = (std::abs(nn.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY()).cross(nn).normalized();
    const Vec3 e2 = nn.cross(e1);
    std::sort(unique.begin(), unique.end(), [&](const Vec3& a, const Vec3& b) {
      return std::atan2((a - centre).dot(e2), (a - centre).dot(e1)) < std::atan2((b - centre).dot(e2), (b - centre).dot(e1));
    });
    out.push_back(std::move(unique));
  }
  return out;
}

// The core solid as polygons (body frame); a cylinder as a 64-sided prism.
std::vector<Polygon> core_polygons(const DieModel& m) {
  std::vector<Polygon> faces;
  if (m.curved()) {
    const int k = 64;
    const Vec3 a = m.rims.axis, p = m.rims.perp, q = a.cross(p);
    const double rad = m.rims.radius + m.rounding, half = m.rims.half + m.rounding;
    Polygon top, bottom;
    for (int i = 0; i < k; ++i) {
      const double phi = 2.0 * M_PI * i / k;
      const Vec3 r = rad * (std::cos(phi) * p + std::sin(phi) * q);
      top.push_back(m.rims.centre + half * a + r);
      bottom.insert(bottom.begin(), m.rims.centre - half * a + r);
    }
    for (int i = 0; i < k; ++i) {
      const std::size_t j = static_cast<std::size_t>((i + 1) % k), ii = static_cast<std::size_t>(i);
      const Vec3 r0 = top[ii] - half * a, r1 = top[j] - half * a;  // at the centre plane
      faces.push_back({r0 - half * a, r1 - half * a, r1 + half * a, r0 + half * a});
    }
    faces.push_back(top);
    faces.push_back(bottom);
    return faces;
  }
  for (int f = 0; f < m.face_count(); ++f) {
    Polygon p;
    for (const int v : m.face_vertices(f)) p.push_back(m.vertices[static_cast<std::size_t>(v)]);
    faces.push_back(std::move(p));
  }
  return faces;
}

std::string face_text(const DieModel& m, int f) {
  if (m.curved() && f < static_cast<int>(kCylinderOutcomeNames.size())) return kCylinderOutcomeNames[static_cast<std::size_t>(f)];
  return std::to_string(m.face_labels[static_cast<std::size_t>(f)]);
}

std::string outcome_text(const DieModel& m, int outcome) {
  if (outcome < 0) return "";
  const std::vector<std::string> names = outcome_names(m);
  if (!names.empty()) return names[static_cast<std::size_t>(outcome)];
  return std::to_string(m.outcome_labels[static_cast<std::size_t>(outcome)]);
}

double energy(const DieModel& m, const RigidState& s) {
  const double rot = 0.5 * s.omega.dot(world_inertia(m, s.R) * s.omega);
  return 0.5 * m.mass * s.velocity.squaredNorm() + rot + m.mass * m.gravity * s.position.z();
}

json frame(double t, const RigidState& s) {
  const Quat q(s.R);
  return json::array({r7(t), r7(s.position.x()), r7(s.position.y()), r7(s.position.z()), r7(q.x()), r7(q.y()), r7(q.z()),
                      r7(q.w())});
}

// What touched at an impact: one corner, an edge (two), a face (three or more); a cylinder's rim.
std::string impact_kind(const DieModel& m, const RigidState& before, int& corners) {
  const ContactSet set = touching_corners(m, before, 1e-6 * m.bounding_radius);  // the models' set tolerance
  corners = set.n;
  if (m.curved()) return set.n >= 3 ? "face" : "rim";
  return set.n <= 1 ? "corner" : set.n == 2 ? "edge" : "face";
}

}  // namespace

json die_json(const DieModel& m, const SceneDef& def) {
  json d;
  d["kind"] = m.curved() ? "cylinder" : "polytope";
  d["name"] = m.name;
  d["shape"] = m.kind;
  d["rounding"] = r7(m.rounding);
  d["bounding_radius"] = r7(m.bounding_radius);
  d["read_down"] = m.read_down;
  d["vertices"] = json::array();
  for (const Vec3& v : m.vertices) d["vertices"].push_back(vec(v));
  d["faces"] = json::array();
  for (int f = 0; f < m.face_count(); ++f) {
    json face;
    face["label"] = m.face_labels[static_cast<std::size_t>(f)];
    face["text"] = face_text(m, f);
    face["normal"] = vec(m.face_normals[static_cast<std::size_t>(f)]);
    face["loop"] = json::array();
    if (!m.curved())
      for (const int v : m.face_vertices(f)) face["loop"].push_back(v);
    d["faces"].push_back(face);
  }
  if (m.curved())
    d["cylinder"] = {{"centre", vec(m.rims.centre)}, {"axis", vec(m.rims.axis)}, {"perp", vec(m.rims.perp)},
                     {"radius", r7(m.rims.radius + m.rounding)}, {"half", r7(m.rims.half + m.rounding)}};
  // Geometric frame -> body frame: x_body = G (x_geo - com_geo).
  const Mat3& G = m.geo_to_body;
  const Vec3& com_geo = m.mass_geometric.com;
  d["geometric_centre"] = vec(G * (Vec3::Zero() - com_geo));
  d["com_offset_mm"] = r7(1e3 * com_geo.norm());
  d["regions"] = json::array();
  const double eps = 1e-9 * std::max(m.bounding_radius, 1e-6);
  for (const RegionDef& region : def.die.regions) {
    std::vector<Polygon> solid = core_polygons(m);
    for (const HalfSpace& h : region.half_spaces) {
      // n.x_geo <= off with x_geo = G^T x_body + com_geo  =>  (G n).x_body <= off - n.com_geo
      const double len = h.normal.norm();
      if (len == 0.0) continue;
      solid = clip(solid, G * (h.normal / len), (h.offset - h.normal.dot(com_geo)) / len, eps);
      if (solid.empty()) break;
    }
    json polys = json::array();
    for (const Polygon& p : solid) {
      json poly = json::array();
      for (const Vec3& v : p) poly.push_back(vec(v));
      polys.push_back(poly);
    }
    d["regions"].push_back({{"material", region.material}, {"polygons", polys}});
  }
  d["base_material"] = def.die.base_material;
  return d;
}

namespace {

// A state the toss went through: the release, an impact's before and after, a fixed step's end.
struct Known {
  double t;
  RigidState s;
  bool step = false;  // recorded by the stepper (sustained contact, `stepped`'s whole toss)
};

// The stepper's states as the toss takes them, kept at most one per frame_dt of toss time (the last
// one before each frame_dt has passed since the one kept before it: no gap between kept states is
// longer than frame_dt or one step) and every phase's last (a lift-off's flight starts from it).
// A phase's last state is the one on_step is given twice, at the same time.
class StepRecorder final : public StepObserver {
 public:
  explicit StepRecorder(double frame_dt) : dt_(frame_dt) {}
  void on_step(double t, const RigidState& s) override {
    if (pending_ && t == pending_->t) {  // the phase's end
      keep({t, s, true});
      pending_.reset();
      return;
    }
    if (pending_ && t - last_ > dt_) keep(*pending_);
    pending_ = Known{t, s, true};
  }
  std::vector<Known> take() {
    if (pending_) keep(*pending_);
    pending_.reset();
    return std::move(kept_);
  }

 private:
  void keep(const Known& k) {
    kept_.push_back(k);
    last_ = k.t;
  }
  double dt_;
  double last_ = -1.0;
  std::optional<Known> pending_;
  std::vector<Known> kept_;
};

}  // namespace

json toss_json(const DieModel& m, std::uint64_t seed, std::uint64_t index, double frame_dt) {
  std::vector<BounceRecord> impacts;
  RigidState final_state;
  const bool have_final = m.fidelity == Fidelity::Impulse || m.fidelity == Fidelity::Stepped;
  StepRecorder recorder(frame_dt);
  TossProbe probe;
  probe.trace = &impacts;
  probe.final_state = &final_state;
  probe.steps_observer = &recorder;
  const TossResult r = toss(m, seed, index, &probe);
  const InitialState init = draw_initial_state(m.throw_, seed, index, m.fidelity != Fidelity::Static);
  const RigidState s0 = to_body_state(m, init);

  json t;
  t["seed"] = seed;
  t["index"] = index;
  t["fidelity"] = to_string(m.fidelity);
  t["status"] = to_string(r.status);
  t["face"] = r.face;
  t["face_index"] = r.face_index;
  t["outcome"] = outcome_text(m, r.outcome);
  t["t_end"] = r7(r.t_end);
  t["bounces"] = r.bounces;

  // The states the toss went through, in time order: the release, each impact's before and after,
  // the fixed steps' (sustained contact; `stepped`'s whole toss) as StepRecorder keeps them, the
  // end. Between steps the page interpolates (they are at most frame_dt or one step apart); from
  // any other state, and from a phase's last step, flight is exact until the next contact and
  // sampled every frame_dt. A stretch where that flight does not land on the next state recorded
  // (none is expected now that steps are recorded) is listed in "interpolated".
  std::vector<Known> known{{0.0, s0}};
  for (const BounceRecord& b : impacts) {
    known.push_back({b.t, b.before});
    known.push_back({b.t, b.after});
  }
  for (Known& k : recorder.take()) known.push_back(std::move(k));
  // Impacts before steps at equal times (a phase entered right after an impact); a step at the
  // time of the state before it (a phase that took no step) adds nothing.
  std::stable_sort(known.begin(), known.end(), [](const Known& a, const Known& b) { return a.t < b.t; });
  std::vector<Known> merged;
  for (Known& k : known)
    if (!(k.step && !merged.empty() && k.t == merged.back().t)) merged.push_back(std::move(k));
  known = std::move(merged);
  if (have_final && r.t_end > known.back().t) known.push_back({r.t_end, final_state});
  const bool moves = r.status != TossStatus::Invalid && m.fidelity != Fidelity::Static;

  json frames = json::array();
  json interpolated = json::array();
  std::size_t steps_kept = 0;
  for (std::size_t i = 0; i < known.size(); ++i) {
    const Known& k = known[i];
    frames.push_back(frame(k.t, k.s));
    steps_kept += k.step ? 1 : 0;
    const bool last = i + 1 == known.size();
    const double gap = (last ? r.t_end : known[i + 1].t) - k.t;
    if (!moves || !(gap > 0.0)) continue;
    double flight_end = gap;
    if (!last && known[i + 1].step) {
      // Within the stepper's phase: the next step is the motion. Only a `stepped` coast (its
      // closed-form steps high above the floor) leaves a gap: free flight, drawn as exact flight.
      if (m.fidelity != Fidelity::Stepped || !k.step || gap <= 2.0 * std::max(frame_dt, m.step)) continue;
    }
    const Flight fl(m, k.s);
    if (!last && !known[i + 1].step && m.fidelity != Fidelity::Paper) {
      const RigidState landed = fl.state(gap);
      if ((landed.position - known[i + 1].s.position).norm() > 1e-6 * m.bounding_radius) {
        const ContactSearch c = fl.next_contact(gap);
        flight_end = c.outcome == ContactSearch::Outcome::Contact ? c.t : 0.0;
        interpolated.push_back({r7(k.t + flight_end), r7(k.t + gap)});
      }
    }
    for (double tau = frame_dt; tau < flight_end - 0.25 * frame_dt; tau += frame_dt) frames.push_back(frame(k.t + tau, fl.state(tau)));
    if (flight_end > 0.0 && flight_end < gap) frames.push_back(frame(k.t + flight_end, fl.state(flight_end)));
    if (last) frames.push_back(frame(k.t + gap, fl.state(gap)));
  }
  t["frames"] = frames;
  t["interpolated"] = interpolated;
  t["steps_recorded"] = steps_kept;

  json imp = json::array();
  for (const BounceRecord& b : impacts) {
    int corners = 0;
    const std::string kind = impact_kind(m, b.before, corners);
    imp.push_back({{"t", r7(b.t)}, {"kind", kind}, {"corners", corners}, {"vertex", b.vertex}, {"impulse", r7(b.impulse)},
                   {"energy_before", r7(energy(m, b.before))}, {"energy_after", r7(energy(m, b.after))}});
  }
  t["impacts"] = imp;
  t["energy_start"] = r7(energy(m, s0));
  return t;
}

}  // namespace dicesim::web

#include "sim/models/world_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dicesim::world_detail {

PlacedHull placed(const World& w, int k, const RigidState& s) {
  const DieModel& d = w.dice[static_cast<std::size_t>(k)];
  return PlacedHull{d.vertices, d.face_normals, w.die_edges[static_cast<std::size_t>(k)], s.R, s.position};
}

PlacedHull placed(const ObstaclePiece& p) {
  return PlacedHull{p.corners, p.face_normals, p.edge_dirs, Mat3::Identity(), Vec3::Zero()};
}

double axis_gap(std::span<const Vec3> a, double ra, std::span<const Vec3> b, double rb, const Vec3& n) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vec3& x : a) lo = std::min(lo, n.dot(x));
  for (const Vec3& y : b) hi = std::max(hi, n.dot(y));
  return lo - hi - ra - rb;
}

Touch touch_piece(const World& w, int k, const RigidState& s, const ObstaclePiece& p, SeparationCache* cache) {
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
                SeparationCache* cache) {
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

Touch far_apart(double gap) {
  Touch t;
  t.gap = gap;
  t.exact = false;
  return t;
}

Mat3 to_normal_frame(const Vec3& n) { return Quat::FromTwoVectors(n, Vec3::UnitZ()).toRotationMatrix(); }

namespace {

// An empty patch (the features' overlap lost to rounding) falls back to the witness point, counted.
ContactPatch or_witness(ContactPatch patch, const Touch& t, std::uint64_t* witness_only) {
  if (patch.n > 0) return patch;
  patch.points[0] = t.point;
  patch.n = 1;
  if (witness_only) ++*witness_only;
  return patch;
}

}  // namespace

ContactPatch piece_patch(const DieModel& d, std::span<const Vec3> mine, const ObstaclePiece& p, const Touch& t,
                         double tol, std::uint64_t* witness_only) {
  const double level_b = t.normal.dot(t.point) - t.gap;
  return or_witness(contact_patch({mine, d.rounding},
                                  {p.plane ? std::span<const Vec3>{} : std::span<const Vec3>(p.corners), 0.0},
                                  t.normal, level_b + t.gap, level_b, tol),
                    t, witness_only);
}

ContactPatch dice_patch(const DieModel& di, std::span<const Vec3> ci, const DieModel& dj, std::span<const Vec3> cj,
                        const Touch& t, double tol, std::uint64_t* witness_only) {
  const double mid = t.normal.dot(t.point);
  return or_witness(contact_patch({ci, di.rounding}, {cj, dj.rounding}, t.normal, mid + 0.5 * t.gap,
                                  mid - 0.5 * t.gap, tol),
                    t, witness_only);
}

double patch_approach(const ContactPatch& patch, const RigidState& si, const RigidState* sj, const Vec3& n,
                      int* fastest) {
  double un = std::numeric_limits<double>::infinity();
  for (int q = 0; q < patch.n; ++q) {
    const Vec3& x = patch.points[static_cast<std::size_t>(q)];
    const double u = (sj ? point_velocity(si, x) - point_velocity(*sj, x) : point_velocity(si, x)).dot(n);
    if (u < un) {
      un = u;
      if (fastest) *fastest = q;
    }
  }
  return un;
}

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
  // The speeds involved, as the floor's law takes them (friction_impact.cpp): the witness point
  // approaching by less than 1e-10 of them after the patch's solve is rounding, not approach.
  const double speed =
      s.velocity.norm() + s.omega.norm() * d.bounding_radius + 1e-2 * std::sqrt(d.gravity * d.bounding_radius);
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
  if ((q.velocity + q.omega.cross(w_point)).z() < -1e-10 * speed) {
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

bool held_still(const DieModel& d, const RigidState& s, std::span<const HeldTouch> touches, double tau) {
  struct Point {
    Vec3 r, n, t1, t2;
    Mat3 W;  // the point's velocity change per unit impulse there
    double inv_wnn = 0.0, mu = 0.0, pn = 0.0;
    Eigen::Matrix2d inv_wtt;
    Eigen::Vector2d pt = Eigen::Vector2d::Zero();
  };
  std::array<Point, (kMaxHolds + 1) * kMaxPatchPoints> pts;
  std::size_t np = 0;
  const Mat3 inv_i = inverse_inertia(d, s.R);
  for (const HeldTouch& h : touches)
    for (int q = 0; q < h.patch.n && np < pts.size(); ++q) {
      Point& p = pts[np++];
      p.r = h.patch.points[static_cast<std::size_t>(q)] - s.position;
      p.n = h.normal;
      p.t1 = h.normal.unitOrthogonal();
      p.t2 = h.normal.cross(p.t1);
      Mat3 X;
      X << 0.0, -p.r.z(), p.r.y(), p.r.z(), 0.0, -p.r.x(), -p.r.y(), p.r.x(), 0.0;
      p.W = Mat3::Identity() / d.mass - X * inv_i * X;
      p.inv_wnn = 1.0 / p.n.dot(p.W * p.n);
      Eigen::Matrix2d wtt;
      wtt << p.t1.dot(p.W * p.t1), p.t1.dot(p.W * p.t2), p.t2.dot(p.W * p.t1), p.t2.dot(p.W * p.t2);
      p.inv_wtt = wtt.inverse();
      p.mu = h.mu;
    }
  if (np == 0) return false;
  Vec3 v = -d.gravity * tau * Vec3::UnitZ(), w = Vec3::Zero();
  const auto apply = [&](const Point& p, const Vec3& P) {
    v += P / d.mass;
    w += inv_i * p.r.cross(P);
  };
  const double still = 1e-6 * d.gravity * tau;
  double last = std::numeric_limits<double>::infinity();  // the residual ten sweeps ago
  for (int sweep = 0; sweep < kHeldSweeps; ++sweep) {
    for (std::size_t k = 0; k < np; ++k) {
      Point& p = pts[k];
      Vec3 u = v + w.cross(p.r);
      const double pn = std::max(0.0, p.pn - u.dot(p.n) * p.inv_wnn);
      apply(p, (pn - p.pn) * p.n);
      p.pn = pn;
      u = v + w.cross(p.r);
      Eigen::Vector2d pt = p.pt - p.inv_wtt * Eigen::Vector2d(u.dot(p.t1), u.dot(p.t2));
      const double limit = p.mu * p.pn, norm = pt.norm();
      if (norm > limit) pt *= limit / norm;
      const Eigen::Vector2d dp = pt - p.pt;
      apply(p, dp.x() * p.t1 + dp.y() * p.t2);
      p.pt = pt;
    }
    const double residual = v.norm() + w.norm() * d.bounding_radius;
    if (residual <= still) return true;
    if (sweep % 10 == 9) {  // stalled: the least kinetic energy the cones allow is not zero
      if (residual > 0.99 * last) return false;
      last = residual;
    }
  }
  return false;
}

HeldTouch floor_touch(const DieModel& d, const RigidState& s, double within) {
  HeldTouch h;
  h.mu = *std::min_element(d.vertex_friction.begin(), d.vertex_friction.end());
  for (const Vec3& c : d.vertices) {
    const Vec3 x = s.position + s.R * c - d.rounding * Vec3::UnitZ();
    if (x.z() <= within && h.patch.n < kMaxPatchPoints) h.patch.points[static_cast<std::size_t>(h.patch.n++)] = x;
  }
  return h;
}

Vec3 point_velocity(const RigidState& s, const Vec3& x) { return s.velocity + s.omega.cross(x - s.position); }

Mat3 inverse_inertia(const DieModel& d, const Mat3& R) {
  return R * d.principal_moments.cwiseInverse().asDiagonal() * R.transpose();
}

}  // namespace dicesim::world_detail

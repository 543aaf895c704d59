// The contact points' set-up shared by a step's solves (ContactGeometry, friction_impact.hpp), and
// the touching corners of a state (touching_corners).
#include "sim/dynamics/friction_impact.hpp"
#include "sim/dynamics/friction_impact_internal.hpp"

#include <algorithm>
#include <cmath>

namespace dicesim {

namespace friction_detail {

// The sweeps' and the direct multi-point solves' terms of the set-up (ContactPoints::sweep_terms).
void set_up_sweep_terms(ContactGeometry& geo) {
  Points& pts = geo.pts;
  if (pts.sweep_terms) return;
  for (int i = 0; i < pts.n; ++i) {
    pts.inv_wtt[i] = pts.wtt[i].inverse();
    const Vec3& r = pts.r[i];
    pts.ax[i] = geo.inv_inertia * Vec3(0.0, r.z(), -r.y());
    pts.ay[i] = geo.inv_inertia * Vec3(-r.z(), 0.0, r.x());
    pts.az[i] = geo.inv_inertia * Vec3(r.y(), -r.x(), 0.0);
  }
  pts.sweep_terms = true;
}

// The part of a solve's set-up that depends only on the orientation R and the contact set; the
// points' lever arms r (from the COM, world), or (null) the contact set's features' own.
void set_up_geometry(const DieModel& m, const Body& b, const Mat3& R, const ContactSet& c, ContactGeometry& geo,
                     const Vec3* r) {
  if (!geo.iw_given) geo.Iw = world_inertia(m, R);
  geo.inv_inertia = b.inv_inertia;
  Points& pts = geo.pts;
  pts.n = c.n;
  // The lever arms in one contact plane: every point at the lowest one's height. Touching corners
  // differ in height by up to the touch tolerance (a face landing a few 1e-9 m out of level); with
  // each corner's own height, the tangential velocities of a face's corners depend on the plane's
  // tilt, no motion makes all of them stick, the true solution slips at ~1e-9 of the speeds, and
  // the solves stall there (pgs_unconverged on faces of Die 3 and the prisms). In one plane the
  // face's problem is exactly consistent. (The lowest, not the mean: independent of the order.)
  // Only points within the largest touch tolerance of the callers (1e-6 r) of the lowest: a set
  // spread wider (a cylinder sunk into the floor by the stepper's drift, both rims' lowest points
  // "touching") keeps its own geometry rather than a lever arm moved by a visible amount.
  double plane_z = 0.0, top_z = 0.0;
  std::optional<RimFeatures> rims;  // a cylinder's points share their set-up
  if (!r && m.curved()) rims.emplace(m, R);
  for (int i = 0; i < c.n; ++i) {
    pts.r[i] = r ? r[i] : rims ? rims->point(c.vertex[i]) : contact_point(m, R, c.vertex[i]);
    plane_z = i == 0 ? pts.r[i].z() : std::min(plane_z, pts.r[i].z());
    top_z = i == 0 ? pts.r[i].z() : std::max(top_z, pts.r[i].z());
  }
  const bool one_plane = top_z - plane_z <= 1e-6 * m.bounding_radius;
  for (int i = 0; i < c.n; ++i) {
    const int v = c.vertex[i];
    if (one_plane) pts.r[i].z() = plane_z;
    pts.e[i] = m.vertex_restitution[v];
    pts.mu[i] = m.vertex_friction[v];
    const Mat3 W = compliance(b, pts.r[i]);
    if (i == 0) pts.W0 = W;
    pts.inv_wnn[i] = 1.0 / W(2, 2);
    pts.wtt[i] = W.topLeftCorner<2, 2>();
    pts.wz[i] = W.col(2);
  }
  pts.sweep_terms = false;
  if (c.n == 1) pts.W0_inverse = pts.W0.inverse();
  else set_up_sweep_terms(geo);  // (one point: only if its exact solve falls back to the sweeps)
  geo.valid = true;
}

}  // namespace friction_detail

ContactSet touching_corners(const DieModel& m, const RigidState& s, double tol) {
  ContactSet c;
  double z[kMaxContacts];
  const int nv = m.vertex_count();
  std::optional<RimFeatures> rims;  // a cylinder's six features share their set-up
  if (m.curved()) rims.emplace(m, s.R);
  for (int i = 0; i < nv; ++i) {
    const double zi = rims ? s.position.z() + rims->point(i).z() : corner_height(m, s, i);
    if (zi > tol) continue;
    if (c.n < kMaxContacts) {
      z[c.n] = zi;
      c.vertex[c.n++] = i;
      continue;
    }
    ++c.dropped;  // full: one corner is left out (replace the highest if this one is lower)
    int hi = 0;
    for (int k = 1; k < c.n; ++k)
      if (z[k] > z[hi]) hi = k;
    if (zi < z[hi]) {
      z[hi] = zi;
      c.vertex[hi] = i;
    }
  }
  // Ascending vertex order, as the stepper's search for new contacts expects.
  for (int a = 1; a < c.n; ++a)
    for (int b = a; b > 0 && c.vertex[b - 1] > c.vertex[b]; --b) std::swap(c.vertex[b - 1], c.vertex[b]);
  return c;
}

}  // namespace dicesim

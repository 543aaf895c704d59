#include "sim/dynamics/contact.hpp"

namespace dicesim {

Impact apply_vertex_impact(const DieModel& m, RigidState& s, int vertex) {
  Impact out;
  const Vec3 r = contact_point(m, s.R, vertex);
  out.contact_point = r;
  const double vn = s.velocity.z() + (s.omega.x() * r.y() - s.omega.y() * r.x());  // (v + w x r).z
  if (vn >= 0.0) return out;

  // I_w^-1 = R diag(1/I) R^T, applied without forming it.
  const auto inv_world = [&](const Vec3& x) -> Vec3 {
    return s.R * (s.R.transpose() * x).cwiseQuotient(m.principal_moments);
  };
  const Vec3 n = Vec3::UnitZ();
  const Vec3 rxn = r.cross(n);
  const double k = 1.0 / m.mass + n.dot(inv_world(rxn).cross(r));
  const double e = m.vertex_restitution[vertex];
  const double j = -(1.0 + e) * vn / k;

  s.velocity.z() += j / m.mass;
  s.omega += inv_world(rxn * j);
  out.impulse = j;
  return out;
}

double kinetic_energy(const DieModel& m, const RigidState& s) {
  const Vec3 wb = s.R.transpose() * s.omega;
  return 0.5 * m.mass * s.velocity.squaredNorm() + 0.5 * wb.dot(m.principal_moments.cwiseProduct(wb));
}

}  // namespace dicesim

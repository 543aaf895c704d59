// The compiled die as JSON (`dicesim info --json` and the Python module): shape, counts, per face
// label, normal, area, stable and p_static, mass properties, corners, fidelity, resting geometry.
#include "apps/info_json.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "sim/body/outcome.hpp"
#include "sim/body/world.hpp"
#include "sim/models/fidelity_models.hpp"

namespace dicesim {
namespace {

nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
nlohmann::json mat(const Mat3& m) { return {vec(m.row(0)), vec(m.row(1)), vec(m.row(2))}; }

// Resting geometry: per face, the COM height on it, the lowest pass out of its basin and the lowest
// pass to a basin read otherwise (where the outcome settles).
nlohmann::json rest_json(const DieModel& m) {
  nlohmann::json faces = nlohmann::json::array();
  for (std::size_t f = 0; f < m.face_normals.size(); ++f)
    faces.push_back({{"label", m.face_labels[f]},
                     {"height", m.face_height[f]},
                     {"escape_height", std::isfinite(m.face_escape[f]) ? nlohmann::json(m.face_escape[f]) : nlohmann::json()},
                     {"outcome_escape_height",
                      std::isfinite(m.outcome_escape[f]) ? nlohmann::json(m.outcome_escape[f]) : nlohmann::json()},
                     {"tip_ratio", m.face_tip_ratio[f]}});
  return faces;
}

// What the die is made of: the base material's part, then each region (m^3, kg).
nlohmann::json parts_json(const std::vector<MaterialPart>& given) {
  nlohmann::json parts = nlohmann::json::array();
  for (const MaterialPart& p : given)
    parts.push_back({{"part", p.what}, {"material", p.material}, {"density", p.density}, {"volume", p.volume}, {"mass", p.mass}});
  return parts;
}

Vec3 geometric_normal(const DieModel& m, std::size_t f) { return m.geo_to_body.transpose() * m.face_normals[f]; }

// A cylinder's own description (its "corners" are moving rim points, so that list is empty): outer
// size, the outcome labels by name, and its two core rim circles in the geometric frame with the
// materials at each (rim k's features are 3 k .. 3 k + 2; they share one material mix).
nlohmann::json cylinder_json(const DieModel& m) {
  const Rims& r = m.rims;
  const Mat3 to_geo = m.geo_to_body.transpose();
  const Vec3& com = m.mass_geometric.com;
  nlohmann::json labels = nlohmann::json::object();
  for (std::size_t f = 0; f < kCylinderOutcomeNames.size() && f < m.face_labels.size(); ++f)
    labels[kCylinderOutcomeNames[f]] = m.face_labels[f];
  nlohmann::json rims = nlohmann::json::array();
  for (int k = 0; k < 2; ++k) {
    const double sgn = k == 0 ? 1.0 : -1.0;
    const std::size_t feature = static_cast<std::size_t>(3 * k);
    nlohmann::json rim = {{"face", kCylinderOutcomeNames[static_cast<std::size_t>(k)]},
                          {"centre", vec(to_geo * (r.centre + sgn * r.half * r.axis) + com)},
                          {"normal", vec(to_geo * (sgn * r.axis))},
                          {"radius", r.radius}};
    if (feature < m.vertex_restitution.size()) {
      rim["restitution"] = m.vertex_restitution[feature];
      rim["friction"] = m.vertex_friction[feature];
    }
    if (feature < m.vertex_rolling.size()) rim["rolling_resistance"] = m.vertex_rolling[feature];
    if (feature < m.vertex_pivoting.size()) rim["pivoting_resistance"] = m.vertex_pivoting[feature];
    rims.push_back(rim);
  }
  return {{"radius", r.radius + m.rounding},
          {"height", 2.0 * (r.half + m.rounding)},
          {"rounding", m.rounding},
          {"axis", vec(to_geo * r.axis)},
          {"labels", labels},
          {"rims", rims}};
}

}  // namespace

nlohmann::json info_json(const std::string& path, const DieModel& m, const std::vector<MaterialPart>& parts) {
  const MassProperties& mp = m.mass_geometric;
  double volume = 0.0;
  for (const MaterialPart& p : parts) volume += p.volume;
  const std::vector<double> p_static = static_face_probabilities(m, kInfoStaticDirections);
  nlohmann::json faces = nlohmann::json::array();
  for (std::size_t f = 0; f < m.face_normals.size(); ++f) {
    const Vec3 n = geometric_normal(m, f);
    nlohmann::json face = {{"label", m.face_labels[f]},
                           {"normal", vec(n)},
                           {"area", m.face_area[f]},
                           {"stable", m.face_hold[f] >= 0.0},
                           {"p_static", p_static[f]},
                           {"reads", resting_outcome_label(m, static_cast<int>(f))}};  // the outcome resting on it
    if (std::find(m.own_read_faces.begin(), m.own_read_faces.end(), static_cast<int>(f)) != m.own_read_faces.end())
      face["reads_own"] = true;  // no single face up when it rests on this one
    if (m.kind == "box") face["direction"] = kFaceDirNames[f];
    if (m.curved() && f < kCylinderOutcomeNames.size()) {
      face["direction"] = kCylinderOutcomeNames[f];  // heads (+z), tails (-z), edge: the curved side
      face["curved"] = f == 2;                        // the side has no single normal nor flat area:
      if (f == 2) face["normal"] = nullptr, face["area"] = nullptr;  // null, not a made-up (0, 0, 0)
    }
    faces.push_back(face);
  }
  nlohmann::json corners = nlohmann::json::array();
  for (std::size_t c = 0; c < m.vertices.size(); ++c) {
    const Vec3 geo = m.geo_to_body.transpose() * m.vertices[c] + mp.com;
    corners.push_back({{"position", vec(geo)}, {"restitution", m.vertex_restitution[c]}, {"friction", m.vertex_friction[c]}});
  }
  nlohmann::json j = {{"scene", path},
          {"name", m.name},
          {"shape", m.kind},
          {"convex", m.convex},
          {"rounding", m.rounding},
          {"read", m.read_down ? "down" : "up"},
          {"vertex_count", m.vertex_count()},
          {"face_count", m.face_count()},
          {"outcomes", m.outcome_labels},
          {"mass", mp.mass},
          {"volume", volume},
          {"parts", parts_json(parts)},
          {"com", vec(mp.com)},
          {"inertia", mat(mp.inertia)},
          {"principal_moments", vec(mp.principal_moments)},
          {"principal_axes", mat(mp.principal_axes)},
          {"symmetric_top", m.symmetric_top},
          {"bounding_radius", m.bounding_radius},
          {"faces", faces},
          {"alike", {{"groups", alike_groups(m)}, {"rotations", m.symmetry_rotations}, {"note", m.alike_note}}},
          {"corners", corners},
          {"world", m.world ? nlohmann::json{{"dice", m.world->size()},
                                              {"obstacle_pieces", m.world->pieces.size()},
                                              {"kind", m.world->kind == OutcomeKind::Sum ? "sum" : "tuple"}}
                            : nlohmann::json()},
          {"fidelity", to_string(m.fidelity)},
          {"fidelity_requested", to_string(m.fidelity_requested)},
          {"fidelity_reason", m.fidelity_reason},
          {"rest", rest_json(m)}};
  if (m.curved()) j["cylinder"] = cylinder_json(m);
  return j;
}

}  // namespace dicesim

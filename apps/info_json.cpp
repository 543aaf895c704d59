// The compiled die as JSON (moved unchanged out of cmd_info.cpp so that python/ can link it).
#include "apps/info_json.hpp"

namespace dicesim {
namespace {

nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
nlohmann::json mat(const Mat3& m) { return {vec(m.row(0)), vec(m.row(1)), vec(m.row(2))}; }

// Resting geometry: per face, the COM height on it and the lowest pass over its edges.
nlohmann::json rest_json(const DieModel& m) {
  nlohmann::json faces = nlohmann::json::array();
  for (int f = 0; f < 6; ++f)
    faces.push_back({{"label", m.face_labels[f]}, {"height", m.face_height[f]}, {"escape_height", m.face_escape[f]},
                     {"tip_ratio", m.face_tip_ratio[f]}});
  return faces;
}

}  // namespace

nlohmann::json info_json(const std::string& path, const DieModel& m) {
  const MassProperties& mp = m.mass_geometric;
  nlohmann::json faces = nlohmann::json::array();
  for (int f = 0; f < 6; ++f) {
    Vec3 n = Vec3::Zero();
    n[f / 2] = (f % 2 == 0) ? 1.0 : -1.0;
    faces.push_back({{"label", m.face_labels[f]}, {"direction", kFaceDirNames[f]}, {"normal", vec(n)}});
  }
  nlohmann::json corners = nlohmann::json::array();
  for (int c = 0; c < 8; ++c) {
    const Vec3 geo = m.geo_to_body.transpose() * m.vertices[c] + mp.com;
    corners.push_back({{"position", vec(geo)}, {"restitution", m.vertex_restitution[c]}, {"friction", m.vertex_friction[c]}});
  }
  return {{"scene", path},
          {"name", m.name},
          {"mass", mp.mass},
          {"com", vec(mp.com)},
          {"inertia", mat(mp.inertia)},
          {"principal_moments", vec(mp.principal_moments)},
          {"principal_axes", mat(mp.principal_axes)},
          {"symmetric_top", m.symmetric_top},
          {"bounding_radius", m.bounding_radius},
          {"faces", faces},
          {"corners", corners},
          {"fidelity", to_string(m.fidelity)},
          {"fidelity_requested", to_string(m.fidelity_requested)},
          {"fidelity_reason", m.fidelity_reason},
          {"rest", rest_json(m)}};
}

}  // namespace dicesim

// The compiled, immutable die (as MuJoCo's mjModel): everything a toss reads, computed once
// from a SceneDef. Body frame = principal frame with origin at the centre of mass.
#pragma once

#include <array>
#include <string>

#include "sim/body/mass_properties.hpp"
#include "sim/math.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

struct DieModel {
  // Geometry in the body (principal, COM-centred) frame.
  std::array<Vec3, 8> vertices;        // box corners; index bit k set <=> + side along geometric axis k
  std::array<Vec3, 6> face_normals;    // outward, order +x, -x, +y, -y, +z, -z of the geometric frame
  std::array<int, 6> face_labels;      // label of each face in that order
  std::array<double, 8> vertex_restitution;  // per corner: volume-weighted over the corner's materials
  std::array<double, 8> vertex_friction;
  double bounding_radius = 0.0;        // max |vertex| from the COM

  // Mass properties.
  double mass = 0.0;
  Vec3 principal_moments = Vec3::Ones();  // ascending
  MassProperties mass_geometric;          // the same in the geometric frame (for `info`)
  // geometric frame -> body frame: x_body = geo_to_body * (x_geo - com_geo)
  Mat3 geo_to_body = Mat3::Identity();
  bool symmetric_top = false;

  // Resting geometry (sim/rest.hpp), per face in the order above, body frame:
  std::array<std::array<int, 4>, 6> face_vertices{};  // corners of each face, in cyclic order
  std::array<double, 6> face_height{};   // COM to the face's plane: the COM height resting on it
  std::array<double, 6> face_escape{};   // lowest COM height over any edge of the face (tipping barrier)
  std::array<double, 6> face_tip_ratio{};  // min over edges: (COM projection to edge) / face_height
  double max_escape = 0.0;               // max of face_escape
  double max_friction = 0.0;             // max of vertex_friction

  // Simulation settings, copied from the scene.
  Fidelity fidelity = Fidelity::Paper;             // the model tosses use (never Auto)
  Fidelity fidelity_requested = Fidelity::Paper;   // what the scene asked for (may be Auto)
  std::string fidelity_reason;                     // why `fidelity` (dicesim info prints it)
  double step = 2e-4;                              // `stepped` time step (s)
  double contact_step = 1e-3;                      // `impulse` sustained-contact step (s)
  double gravity = 9.81;
  double stop_speed = 0.1;
  int max_bounces = 1000;
  double max_time = 60.0;

  ThrowDef throw_;  // distributions of the initial state (geometric frame for orientation)
  std::string name;
};

}  // namespace dicesim

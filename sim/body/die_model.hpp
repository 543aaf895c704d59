// The compiled, immutable die (as MuJoCo's mjModel): everything a toss reads, computed once
// from a SceneDef. Body frame = principal frame with origin at the centre of mass.
//
// Any convex die: a core polytope (vertices, faces of any number of corners) optionally swept by
// a ball of radius `rounding`. On a flat floor the lowest point of the die is the lowest point of
// some corner's ball, so every contact is a corner contact whose point lies `rounding` below the
// corner (contact_point() in sim/dynamics/flight.hpp).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "sim/body/mass_properties.hpp"
#include "sim/math.hpp"
#include "sim/scene/scene.hpp"

namespace dicesim {

// A curved die (a cylinder) in the body frame: its core's two rim circles, centre +- half * axis,
// radius `radius` (the rounding, DieModel::rounding, is swept over them as over a polytope's
// corners). Its contact features are moving points of those circles, not corners: feature
// 3 k + j is on rim k (0: the +axis rim, heads' side; 1: the -axis rim), j = 0 the rim's lowest
// point, j = 1, 2 the points 120 deg either side of it (so that a face lying flat stands on a
// tripod). sim/body/rim.hpp computes them.
struct Rims {
  bool on = false;
  Vec3 centre = Vec3::Zero();    // the cylinder's geometric centre
  Vec3 axis = Vec3::UnitZ();     // unit, toward the heads face
  Vec3 perp = Vec3::UnitX();     // a unit vector perpendicular to axis (the lowest point of a flat rim)
  double radius = 0.0;           // core rim radius (outer radius - rounding)
  double half = 0.0;             // core half-height (outer height / 2 - rounding)
};
inline constexpr int kRimFeatures = 6;

struct World;  // sim/body/world.hpp: several dice, obstacles

struct DieModel {
  // Geometry in the body (principal, COM-centred) frame.
  std::vector<Vec3> vertices;              // the core's corners
  std::vector<double> vertex_restitution;  // per corner: volume-weighted over the corner's materials
  std::vector<double> vertex_friction;
  double rounding = 0.0;                   // radius of the ball swept over the core (m)
  double bounding_radius = 0.0;            // max |vertex| + rounding from the COM
  Rims rims;                               // a cylinder: vertices is empty, features are rim points
  std::vector<double> vertex_rolling;      // a cylinder: per rim feature, rolling resistance (m)
  std::vector<double> vertex_pivoting;     // a cylinder: per rim feature, pivoting resistance (m)
  // Corner adjacency along the core's edges (CSR): neighbours of v are
  // vertex_adj[vertex_adj_begin[v] .. vertex_adj_begin[v + 1]).
  std::vector<int> vertex_adj_begin, vertex_adj;
  std::vector<int> vertex_adj_edge;  // parallel to vertex_adj: position in face_loop of the edge v -> neighbour

  // Faces, in the shape's order (for a box +x, -x, +y, -y, +z, -z of the geometric frame).
  std::vector<Vec3> face_normals;   // outward unit normals
  std::vector<int> face_labels;     // label of each face (several faces may share one: grouped outcomes)
  // Face loops (CSR): face f's corners, counter-clockwise seen from outside, are
  // face_loop[face_begin[f] .. face_begin[f + 1]); face_across at the same position k is the face
  // sharing the edge (loop[k], loop[k + 1]).
  std::vector<int> face_begin, face_loop, face_across;
  std::vector<int> loop_face;       // parallel to face_loop: the face of that loop position
  std::vector<double> face_area;    // of the core's face (m^2)

  // Outcomes: the distinct labels ascending ("label order"); counts and reports use this order.
  std::vector<int> outcome_labels;
  std::vector<int> face_outcome;    // per face: index into outcome_labels
  bool read_down = false;           // the result is the face on the floor (a d4), else the face up
  // Per face f lying on the floor: the face that is read (f itself when read_down, else the face
  // whose normal points most nearly up).
  std::vector<int> face_result;
  // Faces on which the die rests with no single face most nearly up (several of different labels
  // tie, e.g. a corner cut off a 3-fold symmetric die): each is read as its own label, so
  // face_result[f] == f (sim/models/compile.cpp states the rule). Empty when there are none.
  std::vector<int> own_read_faces;
  // Outcomes alike by design (sim/body/symmetry.hpp): per outcome, the index of the first outcome
  // of its class; the rotations that carry the die onto itself and the throw keeps; how found.
  std::vector<int> outcome_alike;
  int symmetry_rotations = 1;
  std::string alike_note;

  // Mass properties.
  double mass = 0.0;
  Vec3 principal_moments = Vec3::Ones();  // ascending
  MassProperties mass_geometric;          // the same in the geometric frame (for `info`)
  // geometric frame -> body frame: x_body = geo_to_body * (x_geo - com_geo)
  Mat3 geo_to_body = Mat3::Identity();
  bool symmetric_top = false;

  // Resting geometry (sim/dynamics/rest.hpp), per face, body frame, rounding included:
  std::vector<double> face_height;     // COM height resting on the face
  std::vector<double> face_hold;       // min distance from the COM's foot to the face's edges (< 0: cannot hold it)
  std::vector<double> face_escape;     // lowest pass out of the face's basin (COM height; +inf: no way out)
  // lowest pass out of the region of basins read as the face's outcome, to a basin read as another
  // (COM height; +inf: none): below it the outcome can no longer change (rest.hpp)
  std::vector<double> outcome_escape;
  std::vector<double> face_tip_ratio;  // face_hold / face_height: the friction coefficient that tips it
  std::vector<double> face_gyro;       // |n x I n|: spinning at w about the normal needs a torque w^2 |n x I n|
  double max_escape = 0.0;             // max of the finite outcome_escape
  double max_friction = 0.0;           // max of vertex_friction

  // Simulation settings, copied from the scene.
  Fidelity fidelity = Fidelity::Paper;             // the model tosses use (never Auto)
  Fidelity fidelity_requested = Fidelity::Paper;   // what the scene asked for (may be Auto)
  std::string fidelity_reason;                     // why `fidelity` (dicesim info prints it)
  double step = 2e-4;                              // `stepped` time step (s)
  double contact_step = 1e-3;                      // `impulse` sustained-contact step's ceiling (s)
  double contact_tol = 0.0;                        // ... its error tolerance (sim.contact_tol; 0: fixed steps)
  double sustained_step = 1e-3;                    // the shape's default contact step: impacts are faster than 4 g this (s)
  double gravity = 9.81;
  double stop_speed = 0.1;
  int max_bounces = 1000;
  double max_time = 60.0;
  bool catch_end = false;  // sim.end = "catch": exact flight to the catch time, no floor

  ThrowDef throw_;  // distributions of the initial state (geometric frame for orientation)
  // Several dice or obstacles ([[dice]], [[obstacles]]): the world a toss runs in; this model is then
  // the first die's with the toss's outcomes (outcome_labels: tuples or sums). Null: one die alone.
  std::shared_ptr<const World> world;
  std::string name;
  std::string kind = "box";  // the scene's die.shape
  bool convex = true;        // false: a mesh whose solid is not its hull (contact uses the hull)

  int face_count() const { return static_cast<int>(face_normals.size()); }
  // Corners, or a cylinder's rim features.
  int vertex_count() const { return rims.on ? kRimFeatures : static_cast<int>(vertices.size()); }
  bool curved() const { return rims.on; }
  int outcomes() const { return static_cast<int>(outcome_labels.size()); }
  std::span<const int> face_vertices(int f) const {
    return {face_loop.data() + face_begin[static_cast<std::size_t>(f)],
            static_cast<std::size_t>(face_begin[static_cast<std::size_t>(f) + 1] - face_begin[static_cast<std::size_t>(f)])};
  }
  std::span<const int> neighbours(int v) const {
    return {vertex_adj.data() + vertex_adj_begin[static_cast<std::size_t>(v)],
            static_cast<std::size_t>(vertex_adj_begin[static_cast<std::size_t>(v) + 1] -
                                     vertex_adj_begin[static_cast<std::size_t>(v)])};
  }
};

}  // namespace dicesim

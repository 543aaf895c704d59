// Between contacts: ballistic COM and torque-free rotation, both exact, and the search for the
// next contact by conservative advancement (a step never passes a contact, at any spin).
#pragma once

#include "sim/body/die_model.hpp"
#include "sim/body/rim.hpp"
#include "sim/math.hpp"
#include "sim/dynamics/torque_free.hpp"

namespace dicesim {

// The die's state at one instant (world frame; R maps body -> world).
struct RigidState {
  Vec3 position = Vec3::Zero();  // COM
  Vec3 velocity = Vec3::Zero();
  Mat3 R = Mat3::Identity();
  Vec3 omega = Vec3::Zero();
};

struct ContactSearch {
  enum class Outcome { Contact, TimeLimit, IterationLimit } outcome = Outcome::TimeLimit;
  double t = 0.0;   // time after the flight's start
  int vertex = -1;  // the vertex that touches (Contact)
  int iterations = 0;
  // Contact: the die's state at t, the very numbers Flight::state(t) returns (the search has
  // already evaluated the rotation there; evaluating it again costs two sincos).
  RigidState at;
};

class Flight {
 public:
  // Starts a flight from `s` (its omega sets the constant angular momentum).
  Flight(const DieModel& model, const RigidState& s);

  RigidState state(double t) const;

  // First t in (0, t_limit] at which a vertex reaches the floor moving down.
  ContactSearch next_contact(double t_limit) const;

  const Vec3& angular_momentum() const { return rotation_.angular_momentum(); }

 private:
  // The state at t given the rotation's (R, omega) there.
  RigidState state_with(double t, const Mat3& R, const Vec3& omega) const;

  const DieModel* model_;
  Vec3 p0_, v0_;
  TorqueFreeRotation rotation_;
  double accel_bound_;  // bound on any vertex's downward acceleration
  double contact_tol_;  // a vertex this close to the floor (m) counts as touching
};

// Where corner v touches a floor below it, relative to the COM (world): the lowest point of the
// corner's ball, `rounding` below the corner (the corner itself for a sharp die). A cylinder's
// feature v: a point of a rim circle (sim/body/rim.hpp).
inline Vec3 contact_point(const DieModel& m, const Mat3& R, int v) {
  if (m.curved()) return rim_point(m, R, v);
  Vec3 r = R * m.vertices[static_cast<std::size_t>(v)];
  r.z() -= m.rounding;
  return r;
}

// Height above the floor of corner v's lowest point.
inline double corner_height(const DieModel& m, const RigidState& s, int v) {
  if (m.curved()) return s.position.z() + rim_point(m, s.R, v).z();
  return s.position.z() + s.R.row(2).dot(m.vertices[static_cast<std::size_t>(v)]) - m.rounding;
}

// World angular momentum R diag(I) R^T omega, evaluated as R (I * (R^T omega)) (what Flight uses).
inline Vec3 world_angular_momentum(const DieModel& m, const Mat3& R, const Vec3& omega) {
  return R * m.principal_moments.cwiseProduct(R.transpose() * omega);
}

// World inertia tensor of the die at orientation R: R diag(I) R^T.
inline Mat3 world_inertia(const DieModel& m, const Mat3& R) {
  return R * m.principal_moments.asDiagonal() * R.transpose();
}

}  // namespace dicesim

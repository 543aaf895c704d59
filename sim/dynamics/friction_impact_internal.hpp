// Internal to the friction solve's source files (friction_impact.cpp and the friction_*.cpp,
// contact_geometry.cpp beside it): the body and contact points every solve works on, the sweeps'
// caps and tolerance, the exact solves' acceptance test, and the solves one file hands to another.
// Not part of the public interface (friction_impact.hpp); include it nowhere else.
#pragma once

#include <Eigen/Core>

#include "sim/dynamics/friction_impact.hpp"

namespace dicesim::friction_detail {

inline Mat3 skew(const Vec3& r) {
  Mat3 X;
  X << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  return X;
}

// Sweep caps of the Gauss-Seidel solves; reaching one is counted (pgs_unconverged).
constexpr int kMaxSweeps = 400;
// Sweeps with the cheap tangential update before the exact one takes over.
constexpr int kCheapSweeps = 30;
// Converged when a whole sweep changed the body's velocity (v, and w times the bounding radius)
// by less than this fraction of the speeds involved. (A test on the impulses would never pass on a
// face, whose split of the load over its corners is not unique; the velocities are.)
constexpr double kSweepTolerance = 1e-11;

using Points = ContactPoints;

struct Body {
  double mass, inv_mass;
  Mat3 inv_inertia;  // world
  RigidState* s;
  int* exact_fallbacks = nullptr;  // ImpactResult::exact_fallbacks of the solve, counted where taken
  void count_exact_fallback() const {
    if (exact_fallbacks) ++*exact_fallbacks;
  }
  void apply(const Vec3& r, const Vec3& P) const {
    s->velocity += P * inv_mass;
    s->omega += inv_inertia * r.cross(P);
  }
  Vec3 point_velocity(const Vec3& r) const { return s->velocity + s->omega.cross(r); }
};

// How much a sweep moved the body: |dv| + radius |dw|.
struct SweepProbe {
  Vec3 v, w;
  explicit SweepProbe(const Body& b) : v(b.s->velocity), w(b.s->omega) {}
  double change(const Body& b, double radius) const {
    return (b.s->velocity - v).norm() + radius * (b.s->omega - w).norm();
  }
};

inline Mat3 compliance(const Body& b, const Vec3& r) {
  const Mat3 X = skew(r);
  return b.inv_mass * Mat3::Identity() - X * b.inv_inertia * X;
}

struct SweepResult {
  int sweeps = 0;
  bool converged = true;
  bool dual = false;  // solve_friction: taken by its dual fallback (counted, ImpactResult::dual_solves)
};

struct NewtonResult {
  int iterations = 0;
  bool converged = false;
};

// The exact solves' acceptance tolerances (friction_edge.cpp's solve_friction_edge,
// friction_dual.cpp, friction_exact_plastic.cpp's plastic_verifies).
constexpr double kVerifyCone = 1e-9;   // |P_i| <= R_i (1 + this)
constexpr double kVerifySlip = 1e-9;   // a point slipping less than this fraction of the speeds sticks
constexpr double kVerifyAlign = 1e-6;  // sliding: |P_i / R_i + u_i / |u_i|| <= this

// Coulomb with maximal dissipation at one point, as the exact solves accept it: |P| <= R (to
// kVerifyCone) and, where it slips more than slip_tol and carries friction, P opposite the slip.
inline bool coulomb_verifies(const Eigen::Vector2d& P, const Eigen::Vector2d& u, double R, double slip_tol) {
  if (!P.allFinite() || P.norm() > R * (1.0 + kVerifyCone)) return false;
  const double un = u.norm();
  return un <= slip_tol || !(R > 0.0) || !((P / R + u / un).norm() > kVerifyAlign);
}

// friction_one_corner.cpp: the exact one-point plastic solve.
bool solve_plastic_single(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[]);

// friction_newton.cpp: semismooth Newton's finish of an unconverged Gauss-Seidel solve.
NewtonResult polish_newton(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[], double radius,
                           double speed, const double* fixed_radius = nullptr);

// friction_exact_plastic.cpp: the direct multi-point plastic solves (every point sticking; every
// point sliding; two points by their active sets).
bool solve_sticking(const Body& b, const Mat3& Iw, const Points& pts, double lever, double pn[],
                    Eigen::Vector2d pt[]);
bool solve_sliding(const Body& b, const Points& pts, double speed, double lever, double pn[], Eigen::Vector2d pt[],
                   const Eigen::Vector2d* start = nullptr);
bool solve_plastic_pair(const Body& b, const Mat3& Iw, const Points& pts, double speed, double lever, double pn[],
                        Eigen::Vector2d pt[], const Eigen::Vector2d* gs_slip = nullptr);

// friction_gauss_seidel.cpp: projected Gauss-Seidel, plastic and restitution friction.
SweepResult solve_plastic(const Body& b, const Points& pts, double pn[], Eigen::Vector2d pt[], double radius,
                          double speed);
SweepResult solve_friction(const Body& b, const Points& pts, const double radius[], Eigen::Vector2d pt[],
                           double lever, double speed);

// friction_edge.cpp: the restitution friction's exact solve on an edge.
bool solve_friction_edge(const Body& b, const Points& pts, const double radius[], Eigen::Vector2d pt[], double lever,
                         double speed, int& steps);

// friction_dual.cpp: the restitution friction by its dual (Gauss-Seidel's fallback).
bool solve_friction_dual(const Body& b, const Points& pts, const double radius[], Eigen::Vector2d pt[],
                         double speed, double lever);

// contact_geometry.cpp: a solve's set-up from the orientation and the contact set.
void set_up_sweep_terms(ContactGeometry& geo);
void set_up_geometry(const DieModel& m, const Body& b, const Mat3& R, const ContactSet& c, ContactGeometry& geo,
                     const Vec3* r = nullptr);

}  // namespace dicesim::friction_detail

// Torque-free rotation of a rigid body between contacts: exact, closed form.
// World angular momentum L is constant; the body frame here is the principal frame
// (inertia diagonal, moments I1 <= I2 <= I3). Symmetric tops use regular precession;
// the general case uses Jacobi elliptic functions and the elliptic integral of the
// third kind (Carlson form) for the precession angle, so energy and |L| are conserved to
// rounding at any spin and any flight time.
#pragma once

#include "sim/math.hpp"

namespace dicesim {

class TorqueFreeRotation {
 public:
  // What the set-up derives from the principal moments alone (which case; a symmetric top's axis
  // and inverse moments): for a body whose rotations are set up many times with the same moments
  // (the stepper's trial steps), computed once. The same numbers the moments' constructor uses.
  struct Moments {
    explicit Moments(const Vec3& moments);
    Vec3 I;
    bool general = false;      // no two moments agree (is_symmetric_top false)
    int axis = 2;              // symmetric: the symmetry axis, and the other two in cyclic order
    int p = 0, q = 1;
    double inv_I_axis = 0.0, inv_I_perp = 0.0;
  };

  TorqueFreeRotation() = default;
  // moments: principal moments (ascending, > 0); R0: principal->world rotation at t = 0;
  // L_world: angular momentum in world coordinates (constant). bounds: whether max_omega() and
  // max_alpha() are computed (false: both 0; a trial step's rotation never asks, and they cost
  // a fair share of the set-up).
  TorqueFreeRotation(const Vec3& moments, const Mat3& R0, const Vec3& L_world, bool bounds = true)
      : TorqueFreeRotation(Moments(moments), R0, L_world, bounds) {}
  TorqueFreeRotation(const Moments& moments, const Mat3& R0, const Vec3& L_world, bool bounds = true);

  // Orientation (principal->world) at time t >= 0 after the start.
  Mat3 orientation(double t) const;
  // The orientation's bottom row (world z of each body axis) at time t: all a corner's height needs.
  // Equal to orientation(t).row(2) up to rounding.
  Vec3 bottom_row(double t) const;
  // The bottom row at t of the rotation TorqueFreeRotation(moments, R0, L_world) would give, bit for
  // bit, without setting up the rest of it: a symmetric top's set-up reduced to the row (the same
  // expressions, entry by entry). For a search that asks one row of many rotations (the stepper's
  // support solves).
  static Vec3 bottom_row_at(const Moments& moments, const Mat3& R0, const Vec3& L_world, double t);
  // The same and its time derivative, R(t)^T (e_z x omega(t)) (the model search's Newton slope).
  Vec3 bottom_row(double t, Vec3& rate) const;
  // Orientation and world angular velocity at time t.
  void state(double t, Mat3& R, Vec3& omega_world) const;

  const Vec3& angular_momentum() const { return L_; }
  // Upper bounds over all t: |omega| and |d omega/dt| (for conservative contact advancement).
  double max_omega() const { return max_omega_; }
  double max_alpha() const { return max_alpha_; }
  bool symmetric() const { return kind_ != Kind::General; }

 private:
  enum class Kind { Still, SymmetricTop, General };
  Kind kind_ = Kind::Still;
  Vec3 I_ = Vec3::Ones();
  Mat3 R0_ = Mat3::Identity();
  Vec3 L_ = Vec3::Zero();
  double max_omega_ = 0.0, max_alpha_ = 0.0;
  // Regular precession (Landau-Lifshitz §33, §35): R(t) = Rot(L^, |L| t / I_perp) R0 Rot(e_a, spin_rate t).
  // Rot(L^, alpha) R0 = along + cos(alpha) across + sin(alpha) cross (Rodrigues, precomputed).
  // Also used for a steady rotation about a principal axis of an asymmetric body.
  // (No default values here or in General: a rotation is set up per flight and per trial step, and
  // init_symmetric / init_general set every member their evaluations read; the other struct is
  // never read.)
  struct Symmetric {
    int axis;                // symmetry axis a (principal-frame index)
    int p, q;                // the other two axes, (a, p, q) cyclic
    double precession_rate;  // |L| / I_perp, about L^
    double spin_rate;        // (1/I_a - 1/I_perp) L_a, about the body axis a (L_a constant)
    double inv_I_perp;       // 1 / I_perp
    Mat3 along;              // L^ L^T R0
    Mat3 across;             // R0 - L^ L^T R0
    Mat3 cross;              // [L^]x R0
  } sym_;

  // Asymmetric top: Jacobi's solution (Landau-Lifshitz §37), see torque_free.cpp for the formulas.
  // Body axes: d = the axis L_b circles (never crosses zero), m = the middle moment, c = the
  // other one; L_c = P cn(u), L_m = Q sn(u), L_d = D dn(u) with u = lambda t + u0.
  static constexpr int kMaxLandenLevels = 16;  // 12 suffice down to k'^2 = 5e-324
  struct General {
    bool steady;                    // L along a principal axis exactly: evaluated through sym_
    bool separatrix;                // k == 1 exactly: sn = tanh, cn = dn = sech, no period
    int c, m, d;                    // body indices as above
    int x, y;                       // relabelled frame (x, y, d) is cyclic: body indices of x and y
    double P, Q, D;                 // amplitudes of L_c, L_m, L_d
    double q_ratio;                 // Q / P, finite even when P -> 0
    double sign_P;                  // sign of P (only -1 on the separatrix)
    double k2, kc2;                 // k^2 and k'^2 = 1 - k^2, each computed without cancellation
    double lambda, u0;              // u = lambda t + u0
    double two_K, inv_two_K;        // half period 2K(k) in u
    double n_prime;                 // Pi characteristic: (1/I_c - 1/I_m) / (1/I_m - 1/I_d)
    double two_fK, f0;              // precession integral over 2K, and at u0
    double phi_rate;                // |L| / I_c
    double phi_coeff;               // |L| (1/I_c - 1/I_d) / lambda
    Vec3 inv_I;                     // 1 / moments
    Mat3 frame;                     // F: fixed world frame, third column L^, R(t) = F Rz(phi) B(t)
    // Descending Landen transformation (A&S 16.12) from k down to a negligible modulus.
    int landen_levels;
    double landen_scale;            // prod 1 / (1 + k_n): sn(u|k) from sin(u * scale)
    // k_n and 1 - k_n (accurate near k_n = 1), n = 1..levels; entries past `landen_levels` are
    // never read, and left uninitialised: a rotation is set up per flight and per trial step.
    double landen_k[kMaxLandenLevels];
    double landen_one_minus_k[kMaxLandenLevels];
  } gen_;

  struct JacobiState {
    double sn, cn, dn;  // at u = lambda t + u0
    double f;           // precession integral f(u) (see torque_free.cpp)
  };
  void init_symmetric(int axis, int p, int q, double inv_I_axis, double inv_I_perp, const Vec3& L_body, bool bounds);
  void init_general(const Vec3& L_body, bool bounds);
  JacobiState jacobi_state(double t) const;
  // (Into R: state() hands its caller's matrix, no copy of a returned one.)
  void symmetric_orientation(double t, Mat3& R) const;
  Mat3 symmetric_orientation(double t) const {
    Mat3 R;
    symmetric_orientation(t, R);
    return R;
  }
  Mat3 general_orientation(const JacobiState& js, double t, Vec3* L_body) const;
};

// True when two principal moments agree within a relative 1e-12 (closed-form symmetric top).
bool is_symmetric_top(const Vec3& moments);

}  // namespace dicesim

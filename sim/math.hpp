// Value types for the physics library: Eigen fixed-size vectors and matrices, never heap.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace dicesim {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

inline constexpr double kPi = 3.14159265358979323846;

// Rotation about a principal axis by `angle` (radians), active (rotates vectors).
inline Mat3 rot_x(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
inline Mat3 rot_z(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }

// Classical z-x-z Euler angles (psi, theta, phi), as the seed's Eq. 37: R = Rz(psi) Rx(theta) Rz(phi).
// R maps body coordinates to world coordinates.
inline Mat3 euler_zxz(double psi, double theta, double phi) { return rot_z(psi) * rot_x(theta) * rot_z(phi); }

}  // namespace dicesim

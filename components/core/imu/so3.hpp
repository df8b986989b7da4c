// SO(3) exponential and logarithm maps and the right Jacobian, as the IMU preintegration uses them
// (Forster et al., "On-Manifold Preintegration for Real-Time Visual-Inertial Odometry", T-RO 2017,
// eqs. 3-8). Rotation vectors are in radians; small angles use the series forms.
#pragma once

#include <Eigen/Core>

namespace heslam::so3 {

// [w]x: the cross-product matrix, [w]x v = w x v.
Eigen::Matrix3d hat(const Eigen::Vector3d& w);

// Exp(phi): the rotation by |phi| radians about phi / |phi|.
Eigen::Matrix3d exp(const Eigen::Vector3d& phi);

// Log(R): the rotation vector of R, |phi| in [0, pi]. R must be a rotation matrix.
Eigen::Vector3d log(const Eigen::Matrix3d& R);

// Jr(phi): Exp(phi + d) ~= Exp(phi) Exp(Jr(phi) d) for small d.
Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& phi);

// Jr(phi)^-1: Log(Exp(phi) Exp(d)) ~= phi + Jr(phi)^-1 d for small d.
Eigen::Matrix3d right_jacobian_inverse(const Eigen::Vector3d& phi);

// The nearest rotation to a matrix that drifted from orthonormal by rounding (repeated products).
Eigen::Matrix3d normalized(const Eigen::Matrix3d& R);

}  // namespace heslam::so3

// SO(3) maps for the IMU preintegration (so3.hpp).
#include "components/core/imu/so3.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>
#include <Eigen/SVD>

namespace heslam::so3 {
namespace {

// Below this angle the closed forms divide by ~0; their Taylor series are exact to double precision.
constexpr double kSmallAngleRad = 1e-5;

}  // namespace

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return W;
}

Eigen::Matrix3d exp(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  const Eigen::Matrix3d W = hat(phi);
  if (angle < kSmallAngleRad) return Eigen::Matrix3d::Identity() + W + 0.5 * W * W;
  return Eigen::Matrix3d::Identity() + std::sin(angle) / angle * W + (1.0 - std::cos(angle)) / (angle * angle) * W * W;
}

Eigen::Vector3d log(const Eigen::Matrix3d& R) {
  const double cos_angle = std::clamp(0.5 * (R.trace() - 1.0), -1.0, 1.0);
  const double angle = std::acos(cos_angle);
  const Eigen::Vector3d vee(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  if (angle < kSmallAngleRad) return 0.5 * vee;
  if (M_PI - angle < 1e-6) {
    // Near pi the antisymmetric part vanishes: the axis is the column of R + I with the largest norm.
    const Eigen::Matrix3d S = R + Eigen::Matrix3d::Identity();
    int column = 0;
    S.colwise().norm().maxCoeff(&column);
    Eigen::Vector3d axis = S.col(column).normalized();
    if (axis.dot(vee) < 0.0) axis = -axis;
    return angle * axis;
  }
  return angle / (2.0 * std::sin(angle)) * vee;
}

Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  const Eigen::Matrix3d W = hat(phi);
  if (angle < kSmallAngleRad) return Eigen::Matrix3d::Identity() - 0.5 * W + W * W / 6.0;
  const double angle2 = angle * angle;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(angle)) / angle2 * W +
         (angle - std::sin(angle)) / (angle2 * angle) * W * W;
}

Eigen::Matrix3d right_jacobian_inverse(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  const Eigen::Matrix3d W = hat(phi);
  if (angle < kSmallAngleRad) return Eigen::Matrix3d::Identity() + 0.5 * W + W * W / 12.0;
  return Eigen::Matrix3d::Identity() + 0.5 * W +
         (1.0 / (angle * angle) - (1.0 + std::cos(angle)) / (2.0 * angle * std::sin(angle))) * W * W;
}

Eigen::Matrix3d normalized(const Eigen::Matrix3d& R) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d nearest = svd.matrixU() * svd.matrixV().transpose();
  if (nearest.determinant() < 0.0) {
    Eigen::Matrix3d U = svd.matrixU();
    U.col(2) = -U.col(2);
    nearest = U * svd.matrixV().transpose();
  }
  return nearest;
}

}  // namespace heslam::so3

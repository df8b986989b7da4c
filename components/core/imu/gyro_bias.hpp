// The gyroscope bias from rotations known by other means (vision between keyframes): the first step
// of a visual-inertial initialization (ORB-SLAM3's InitializeIMU solves it jointly; here alone, as
// Forster et al. 2017 section VI-A do). Gauss-Newton on the preintegrated rotations corrected with their
// bias Jacobians: sum_k |Log(dR_k(b)^T R_ij,k)|^2 over the intervals.
#pragma once

#include <span>

#include <Eigen/Core>

#include "components/core/imu/preintegration.hpp"

namespace heslam {

struct GyroBiasEstimate {
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  double rms_residual_rad = 0.0;  // of the rotation residuals at the estimate
  int iterations = 0;
};

// intervals[k] preintegrates [t_i, t_j]; R_ij[k] is the body's rotation over the same interval
// (R_wb(t_i)^T R_wb(t_j)). The estimate starts from the intervals' linearization bias. Throws
// std::invalid_argument for fewer than two intervals or sizes that differ.
GyroBiasEstimate estimate_gyro_bias(std::span<const ImuPreintegration> intervals, std::span<const Eigen::Matrix3d> R_ij,
                                    int max_iterations = 10);

}  // namespace heslam

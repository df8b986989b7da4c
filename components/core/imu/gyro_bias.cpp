// Gyroscope bias from known relative rotations (gyro_bias.hpp).
#include "components/core/imu/gyro_bias.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "components/core/imu/so3.hpp"

namespace heslam {
namespace {

// A Gauss-Newton step below this (rad/s) changes nothing a 200 Hz IMU can resolve.
constexpr double kConvergedStepRadS = 1e-9;

}  // namespace

GyroBiasEstimate estimate_gyro_bias(std::span<const ImuPreintegration> intervals, std::span<const Eigen::Matrix3d> R_ij,
                                    int max_iterations) {
  if (intervals.size() < 2 || intervals.size() != R_ij.size()) {
    throw std::invalid_argument("estimate_gyro_bias: expected at least two intervals, each with its rotation");
  }
  GyroBiasEstimate estimate;
  ImuBias bias = intervals.front().bias();
  const auto residual = [&](std::size_t k) { return so3::log(intervals[k].delta_R(bias).transpose() * R_ij[k]); };
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < intervals.size(); ++k) {
      // r(b + d) = Log(Exp(-J d') Exp(r)) ~= r - Jr(-r)^-1 J d' (d' from the linearization bias).
      const Eigen::Vector3d r = residual(k);
      const Eigen::Matrix3d A = so3::right_jacobian_inverse(-r) * intervals[k].dR_dbg();
      H += A.transpose() * A;
      g += A.transpose() * r;
    }
    const Eigen::Vector3d step = H.ldlt().solve(g);
    bias.gyro_rad_s += step;
    estimate.iterations = iteration + 1;
    if (!step.allFinite()) throw std::invalid_argument("estimate_gyro_bias: the rotations do not constrain the bias");
    if (step.norm() < kConvergedStepRadS) break;
  }
  double sum = 0.0;
  for (std::size_t k = 0; k < intervals.size(); ++k) sum += residual(k).squaredNorm();
  estimate.gyro_rad_s = bias.gyro_rad_s;
  estimate.rms_residual_rad = std::sqrt(sum / static_cast<double>(intervals.size()));
  return estimate;
}

}  // namespace heslam

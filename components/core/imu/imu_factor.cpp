// IMU residuals for Ceres (imu_factor.hpp).
#include "components/core/imu/imu_factor.hpp"

#include <cmath>
#include <stdexcept>

#include "components/core/imu/so3.hpp"

namespace heslam {

ImuIntervalResidual::ImuIntervalResidual(const ImuPreintegration& preintegration, const Matrix9d& extra_covariance)
    : duration_s_(preintegration.duration_s()),
      bias_gyro_(preintegration.bias().gyro_rad_s),
      bias_accel_(preintegration.bias().accel_m_s2),
      delta_R_(preintegration.delta_R()),
      delta_v_(preintegration.delta_v()),
      delta_p_(preintegration.delta_p()),
      dR_dbg_(preintegration.dR_dbg()),
      dv_dbg_(preintegration.dv_dbg()),
      dv_dba_(preintegration.dv_dba()),
      dp_dbg_(preintegration.dp_dbg()),
      dp_dba_(preintegration.dp_dba()) {
  const Matrix9d covariance = preintegration.covariance() + extra_covariance;
  // L with L^T L = information: the upper Cholesky factor of the information.
  const Eigen::LLT<Matrix9d> covariance_llt(covariance);
  if (covariance_llt.info() != Eigen::Success || !covariance.allFinite()) {
    throw std::invalid_argument(
        "ImuIntervalResidual: the preintegration covariance is not positive definite (an interval of a single "
        "IMU step, or zero noise densities)");
  }
  const Matrix9d information = covariance_llt.solve(Matrix9d::Identity());
  const Eigen::LLT<Matrix9d> information_llt(0.5 * (information + information.transpose()));
  if (information_llt.info() != Eigen::Success) {
    throw std::invalid_argument("ImuIntervalResidual: the preintegration information is not positive definite");
  }
  sqrt_information_ = information_llt.matrixU();
}

BiasRandomWalkFactor::BiasRandomWalkFactor(const ImuPreintegration& preintegration) {
  const Eigen::Matrix<double, 6, 6> covariance = preintegration.bias_random_walk_covariance();
  if (!(covariance(0, 0) > 0.0) || !(covariance(3, 3) > 0.0)) {
    throw std::invalid_argument(
        "BiasRandomWalkFactor: expected positive random walks and duration (gyro_random_walk, accel_random_walk)");
  }
  inv_sigma_gyro_ = 1.0 / std::sqrt(covariance(0, 0));
  inv_sigma_accel_ = 1.0 / std::sqrt(covariance(3, 3));
}

Eigen::Matrix<double, 9, 1> imu_residual(const ImuPreintegration& preintegration, const NavState& i,
                                         const ImuBias& bias_i, const NavState& j, const Eigen::Vector3d& gravity_w) {
  const double t = preintegration.duration_s();
  Eigen::Matrix<double, 9, 1> r;
  r.head<3>() = so3::log(preintegration.delta_R(bias_i).transpose() * i.R_wb.transpose() * j.R_wb);
  r.segment<3>(3) = i.R_wb.transpose() * (j.v_wb - i.v_wb - gravity_w * t) - preintegration.delta_v(bias_i);
  r.segment<3>(6) =
      i.R_wb.transpose() * (j.p_wb - i.p_wb - i.v_wb * t - 0.5 * gravity_w * t * t) - preintegration.delta_p(bias_i);
  return r;
}

}  // namespace heslam

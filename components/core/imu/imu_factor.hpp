// Ceres residuals for the IMU between two body states i and j (tracking with IMU, inertial local and
// global BA, the initializer's refinement): the preintegrated rotation, velocity and position against the
// states (Forster et al. 2017, eq. 45), with the increments corrected to the bias at i at first order,
// whitened by the preintegration's information; and the bias random walk between i and j.
//
// Parameter blocks, in the body (IMU) frame b and the world w:
//   q_wb  4  Eigen quaternion x y z w of R_wb (use ceres::EigenQuaternionManifold)
//   p_wb  3  position of the body in w
//   v_wb  3  velocity of the body in w
//   bg    3  gyroscope bias, rad/s
//   ba    3  accelerometer bias, m/s^2
// The camera's pose is T_wb * T_bc: a BA holding camera poses converts with the IMU-camera extrinsic.
// Autodiff: a few microseconds per evaluation, well below the reprojection terms' share of a local BA.
#pragma once

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "components/core/imu/preintegration.hpp"

namespace heslam {

// The residual of one preintegrated interval, whitened, for any scalar type (double or ceres::Jet).
class ImuIntervalResidual {
 public:
  // extra_covariance (rotation, velocity, position order) is added to the preintegration's covariance
  // before whitening: e.g. the uncertainty of poses held fixed (the initializer). Throws
  // std::invalid_argument when the sum is not positive definite (an interval of a single IMU step).
  explicit ImuIntervalResidual(const ImuPreintegration& preintegration,
                               const Matrix9d& extra_covariance = Matrix9d::Zero());

  // residual (9): sqrt_information * (r_R, r_v, r_p) with
  //   r_R = Log(dR(bg)^T R_i^T R_j)
  //   r_v = R_i^T (v_j - v_i - g t) - dv(bg, ba)
  //   r_p = R_i^T (p_j - p_i - v_i t - g t^2 / 2) - dp(bg, ba)
  template <typename T>
  void evaluate(const Eigen::Matrix<T, 3, 3>& R_wi, const Eigen::Matrix<T, 3, 1>& p_wi,
                const Eigen::Matrix<T, 3, 1>& v_wi, const Eigen::Matrix<T, 3, 1>& bg, const Eigen::Matrix<T, 3, 1>& ba,
                const Eigen::Matrix<T, 3, 3>& R_wj, const Eigen::Matrix<T, 3, 1>& p_wj,
                const Eigen::Matrix<T, 3, 1>& v_wj, const Eigen::Matrix<T, 3, 1>& gravity_w, T* residual) const {
    using Vector3 = Eigen::Matrix<T, 3, 1>;
    using Matrix3 = Eigen::Matrix<T, 3, 3>;
    const Vector3 dbg = bg - bias_gyro_.cast<T>();
    const Vector3 dba = ba - bias_accel_.cast<T>();
    const Vector3 correction = dR_dbg_.cast<T>() * dbg;
    Matrix3 correction_R;
    ceres::AngleAxisToRotationMatrix(correction.data(), correction_R.data());
    const Matrix3 dR = delta_R_.cast<T>() * correction_R;
    const Vector3 dv = delta_v_.cast<T>() + dv_dbg_.cast<T>() * dbg + dv_dba_.cast<T>() * dba;
    const Vector3 dp = delta_p_.cast<T>() + dp_dbg_.cast<T>() * dbg + dp_dba_.cast<T>() * dba;
    const T t(duration_s_);
    const Matrix3 error_R = dR.transpose() * R_wi.transpose() * R_wj;
    Eigen::Matrix<T, 9, 1> r;
    ceres::RotationMatrixToAngleAxis(error_R.data(), r.data());
    r.template segment<3>(3) = R_wi.transpose() * (v_wj - v_wi - gravity_w * t) - dv;
    r.template segment<3>(6) = R_wi.transpose() * (p_wj - p_wi - v_wi * t - T(0.5) * gravity_w * t * t) - dp;
    Eigen::Map<Eigen::Matrix<T, 9, 1>> whitened(residual);
    whitened = sqrt_information_.cast<T>() * r;
  }

  double duration_s() const { return duration_s_; }
  // Upper-triangular L with L^T L = (covariance + extra)^-1.
  const Matrix9d& sqrt_information() const { return sqrt_information_; }

 private:
  double duration_s_;
  Eigen::Vector3d bias_gyro_, bias_accel_;
  Eigen::Matrix3d delta_R_;
  Eigen::Vector3d delta_v_, delta_p_;
  Eigen::Matrix3d dR_dbg_, dv_dbg_, dv_dba_, dp_dbg_, dp_dba_;
  Matrix9d sqrt_information_;
};

// The IMU factor between states i and j with a known gravity g_w (e.g. R_wg * (0, 0, -9.81) after
// initialization). Blocks: q_wb_i, p_wb_i, v_wb_i, bg_i, ba_i, q_wb_j, p_wb_j, v_wb_j; 9 residuals.
class ImuFactor {
 public:
  ImuFactor(const ImuPreintegration& preintegration, const Eigen::Vector3d& gravity_w)
      : residual_(preintegration), gravity_w_(gravity_w) {}

  template <typename T>
  bool operator()(const T* q_wi, const T* p_wi, const T* v_wi, const T* bg_i, const T* ba_i, const T* q_wj,
                  const T* p_wj, const T* v_wj, T* residual) const {
    using Vector3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Quaternion<T> qi = Eigen::Map<const Eigen::Quaternion<T>>(q_wi).normalized();
    const Eigen::Quaternion<T> qj = Eigen::Map<const Eigen::Quaternion<T>>(q_wj).normalized();
    residual_.evaluate<T>(qi.toRotationMatrix(), Eigen::Map<const Vector3>(p_wi), Eigen::Map<const Vector3>(v_wi),
                          Eigen::Map<const Vector3>(bg_i), Eigen::Map<const Vector3>(ba_i), qj.toRotationMatrix(),
                          Eigen::Map<const Vector3>(p_wj), Eigen::Map<const Vector3>(v_wj), gravity_w_.cast<T>(),
                          residual);
    return true;
  }

  // The Ceres cost (the caller's problem owns it, as Ceres does by default).
  static ceres::CostFunction* create(const ImuPreintegration& preintegration, const Eigen::Vector3d& gravity_w) {
    return new ceres::AutoDiffCostFunction<ImuFactor, 9, 4, 3, 3, 3, 3, 4, 3, 3>(
        new ImuFactor(preintegration, gravity_w));
  }

 private:
  ImuIntervalResidual residual_;
  Eigen::Vector3d gravity_w_;
};

// The bias random walk between i and j: (bg_j - bg_i, ba_j - ba_i) whitened by the random walks over the
// interval (ImuPreintegration::bias_random_walk_covariance). Blocks bg_i, ba_i, bg_j, ba_j; 6 residuals.
class BiasRandomWalkFactor {
 public:
  explicit BiasRandomWalkFactor(const ImuPreintegration& preintegration);

  template <typename T>
  bool operator()(const T* bg_i, const T* ba_i, const T* bg_j, const T* ba_j, T* residual) const {
    for (int k = 0; k < 3; ++k) {
      residual[k] = (bg_j[k] - bg_i[k]) * T(inv_sigma_gyro_);
      residual[3 + k] = (ba_j[k] - ba_i[k]) * T(inv_sigma_accel_);
    }
    return true;
  }

  static ceres::CostFunction* create(const ImuPreintegration& preintegration) {
    return new ceres::AutoDiffCostFunction<BiasRandomWalkFactor, 6, 3, 3, 3, 3>(
        new BiasRandomWalkFactor(preintegration));
  }

 private:
  double inv_sigma_gyro_, inv_sigma_accel_;
};

// The unwhitened residual (r_R, r_v, r_p) of ImuIntervalResidual for two NavStates: for tests and
// diagnostics.
Eigen::Matrix<double, 9, 1> imu_residual(const ImuPreintegration& preintegration, const NavState& i,
                                         const ImuBias& bias_i, const NavState& j, const Eigen::Vector3d& gravity_w);

}  // namespace heslam

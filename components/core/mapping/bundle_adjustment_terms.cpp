// Analytic reprojection residual and pose manifold for the Ceres bundle adjustment.
// GCC 12 with -march=native (AVX-512) and the sanitizers reports Eigen's vectorised 4-element
// reductions (quaternion norms) as "may be used uninitialized": a known false positive.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "components/core/mapping/bundle_adjustment_terms.hpp"

#include <cmath>

#include <ceres/rotation.h>

namespace heslam {
namespace {

Eigen::Quaterniond quaternion_of(const double* block) {
  return Eigen::Quaterniond(block[3], block[0], block[1], block[2]);
}

Eigen::Quaterniond exp_so3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle));
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

PoseBlock to_pose_block(const Pose3& T_wc) {
  const Pose3 T_cw = T_wc.inverse();
  // Ceres' scalar conversion: Eigen's Quaterniond(Matrix3d) trips a GCC 12 AVX-512 false warning.
  const Eigen::Matrix3d R = T_cw.linear();
  double q_wxyz[4];
  ceres::RotationMatrixToQuaternion(ceres::ColumnMajorAdapter3x3(R.data()), q_wxyz);
  return {q_wxyz[1],
          q_wxyz[2],
          q_wxyz[3],
          q_wxyz[0],
          T_cw.translation().x(),
          T_cw.translation().y(),
          T_cw.translation().z()};
}

Pose3 from_pose_block(const PoseBlock& block) {
  Pose3 T_cw = Pose3::Identity();
  T_cw.linear() = quaternion_of(block.data()).normalized().toRotationMatrix();
  T_cw.translation() = Eigen::Vector3d(block[4], block[5], block[6]);
  return T_cw.inverse();
}

Eigen::Vector3d transform_to_camera(const PoseBlock& block, const Eigen::Vector3d& p_w) {
  return quaternion_of(block.data()).normalized() * p_w + Eigen::Vector3d(block[4], block[5], block[6]);
}

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Quaterniond q = (exp_so3(Eigen::Vector3d(delta[0], delta[1], delta[2])) * quaternion_of(x)).normalized();
  x_plus_delta[0] = q.x();
  x_plus_delta[1] = q.y();
  x_plus_delta[2] = q.z();
  x_plus_delta[3] = q.w();
  for (int i = 0; i < 3; ++i) x_plus_delta[4 + i] = x[4 + i] + delta[3 + i];
  return true;
}

bool PoseManifold::PlusJacobian(const double*, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topLeftCorner<6, 6>().setIdentity();
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const Eigen::AngleAxisd delta(quaternion_of(y) * quaternion_of(x).inverse());
  const Eigen::Vector3d w = delta.angle() * delta.axis();
  for (int i = 0; i < 3; ++i) {
    y_minus_x[i] = w[i];
    y_minus_x[3 + i] = y[4 + i] - x[4 + i];
  }
  return true;
}

bool PoseManifold::MinusJacobian(const double*, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topLeftCorner<6, 6>().setIdentity();
  return true;
}

ReprojectionCost::ReprojectionCost(const PinholeStereo& camera, double u_px, double v_px, double u_right_px,
                                   double inv_sigma, bool stereo, double disparity_sigma_ratio)
    : fx_(camera.fx_px),
      fy_(camera.fy_px),
      cx_(camera.cx_px),
      cy_(camera.cy_px),
      bf_(camera.bf()),
      u_(u_px),
      v_(v_px),
      disparity_(u_px - u_right_px),
      weight_(inv_sigma),
      disparity_weight_(inv_sigma / disparity_sigma_ratio),
      stereo_(stereo) {
  set_num_residuals(stereo ? 3 : 2);
  mutable_parameter_block_sizes()->push_back(7);
  mutable_parameter_block_sizes()->push_back(3);
}

bool ReprojectionCost::Evaluate(const double* const* parameters, double* residuals, double** jacobians) const {
  const Eigen::Matrix3d R = quaternion_of(parameters[0]).normalized().toRotationMatrix();
  const Eigen::Map<const Eigen::Vector3d> p_w(parameters[1]);
  const Eigen::Vector3d Rp = R * p_w;
  const Eigen::Vector3d p_c = Rp + Eigen::Vector3d(parameters[0][4], parameters[0][5], parameters[0][6]);
  if (p_c.z() <= 0.0) return false;  // behind the camera: reject the step
  const double inv_z = 1.0 / p_c.z();
  const double u_hat = fx_ * p_c.x() * inv_z + cx_;
  residuals[0] = weight_ * (u_hat - u_);
  residuals[1] = weight_ * (fy_ * p_c.y() * inv_z + cy_ - v_);
  if (stereo_) residuals[2] = disparity_weight_ * (bf_ * inv_z - disparity_);
  if (jacobians == nullptr) return true;

  // d residual / d p_c, whitened.
  Eigen::Matrix<double, 3, 3> J_pc;
  const double inv_z2 = inv_z * inv_z;
  J_pc << fx_ * inv_z, 0.0, -fx_ * p_c.x() * inv_z2, 0.0, fy_ * inv_z, -fy_ * p_c.y() * inv_z2, 0.0, 0.0, -bf_ * inv_z2;
  J_pc.topRows<2>() *= weight_;
  J_pc.row(2) *= disparity_weight_;
  const int rows = stereo_ ? 3 : 2;
  if (jacobians[0] != nullptr) {
    // p_c(w, r) = Exp(w) R p + t + r  =>  d/dw = -[R p]x, d/dr = I.
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor>> J(jacobians[0], rows, 7);
    J.leftCols<3>() = J_pc.topRows(rows) * (-skew(Rp));
    J.middleCols<3>(3) = J_pc.topRows(rows);
    J.col(6).setZero();
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> J(jacobians[1], rows, 3);
    J = J_pc.topRows(rows) * R;
  }
  return true;
}

}  // namespace heslam

// IMU-only state propagation with covariance (propagation.hpp).
#include "components/core/imu/propagation.hpp"

#include "components/core/imu/so3.hpp"

namespace heslam {

NavStateEstimate propagate(const NavStateEstimate& start, const ImuPreintegration& preintegration, const ImuBias& bias,
                           const Eigen::Vector3d& gravity_w, const Eigen::Matrix<double, 6, 6>& bias_covariance) {
  const double t = preintegration.duration_s();
  const Eigen::Matrix3d& R_wi = start.state.R_wb;
  const Eigen::Matrix3d dR = preintegration.delta_R(bias);
  const Eigen::Vector3d dv = preintegration.delta_v(bias);
  const Eigen::Vector3d dp = preintegration.delta_p(bias);

  NavStateEstimate end;
  end.state = preintegration.predict(start.state, gravity_w, bias);

  // With R_wi Exp(e) at the start: R_wj = R_wi Exp(e) dR = R_wj Exp(dR^T e); v and p take -R_wi [dv]x e
  // and -R_wi [dp]x e. The increments' own errors (right perturbation of dR, additive on dv, dp in the
  // frame of i) enter through B.
  Matrix9d A = Matrix9d::Identity();
  A.block<3, 3>(0, 0) = dR.transpose();
  A.block<3, 3>(3, 0) = -R_wi * so3::hat(dv);
  A.block<3, 3>(6, 0) = -R_wi * so3::hat(dp);
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * t;
  Matrix9d B = Matrix9d::Identity();
  B.block<3, 3>(3, 3) = R_wi;
  B.block<3, 3>(6, 6) = R_wi;
  // The bias enters the increments through their Jacobians (the rotation's correction is Exp(J d) on the
  // right of dR, so at first order it is J d in the end's body frame).
  Eigen::Matrix<double, 9, 6> C = Eigen::Matrix<double, 9, 6>::Zero();
  C.block<3, 3>(0, 0) = preintegration.dR_dbg();
  C.block<3, 3>(3, 0) = R_wi * preintegration.dv_dbg();
  C.block<3, 3>(3, 3) = R_wi * preintegration.dv_dba();
  C.block<3, 3>(6, 0) = R_wi * preintegration.dp_dbg();
  C.block<3, 3>(6, 3) = R_wi * preintegration.dp_dba();
  end.covariance = A * start.covariance * A.transpose() + B * preintegration.covariance() * B.transpose() +
                   C * bias_covariance * C.transpose();
  end.covariance = 0.5 * (end.covariance + end.covariance.transpose());
  return end;
}

}  // namespace heslam

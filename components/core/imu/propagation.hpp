// Carrying the body's state on the IMU alone (a blackout of the images): the predicted state after one
// preintegrated interval and its covariance, grown by the preintegration's noise and, if given, the
// biases' uncertainty. Chained interval by interval it bounds how far the pose may have drifted when the
// images return (Forster et al. 2017, eq. 33 for the state, first-order error propagation for the rest).
#pragma once

#include <Eigen/Core>

#include "components/core/imu/preintegration.hpp"

namespace heslam {

// A state with its covariance. Error convention (rotation, velocity, position order, as Matrix9d):
// R_wb_true = R_wb Exp(d_theta) (a right perturbation, in the body), v and p additive in the world.
struct NavStateEstimate {
  NavState state;
  Matrix9d covariance = Matrix9d::Zero();
};

// The state at the end of `preintegration` from `start`, with gravity g_w and the bias (held constant
// over the interval; the increments are corrected to it at first order). bias_covariance (gyro, then
// accel) is the bias's own uncertainty, propagated through the bias Jacobians; zero ignores it.
NavStateEstimate propagate(const NavStateEstimate& start, const ImuPreintegration& preintegration, const ImuBias& bias,
                           const Eigen::Vector3d& gravity_w,
                           const Eigen::Matrix<double, 6, 6>& bias_covariance = Eigen::Matrix<double, 6, 6>::Zero());

}  // namespace heslam

// The covariance of a tracked camera pose from motion-only BA's information at the optimum: the
// inverse of the Hessian J^T J of the whitened residuals over the pose, scaled by the residual
// variance factor chi2 / (rows - 6) (the observations' sigma model is the keypoint's pyramid level,
// as in motion_only_ba.hpp; the factor rescales it to what the residuals show).
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/tracking/motion_only_ba.hpp"

namespace heslam {

struct PoseCovariance {
  // Of T_wc, perturbed in the world's axes: R_wc' = Exp(rotation) R_wc, position' = position + delta,
  // in the order (rotation x y z [rad], position x y z [m]).
  Eigen::Matrix<double, 6, 6> covariance_wc = Eigen::Matrix<double, 6, 6>::Zero();
  double variance_factor = 0.0;  // chi2 / (rows - 6) of the observations
  int rows = 0;                  // residual rows used (2 per monocular, 3 per stereo observation)
};

// From the inlier observations at the optimized pose T_cw (those in front of the camera count); none
// when they do not constrain all six degrees of freedom (fewer than 7 rows, or a singular Hessian).
std::optional<PoseCovariance> pose_covariance(const PinholeStereo& camera,
                                              const std::vector<PoseObservation>& observations, const Pose3& T_cw,
                                              double disparity_sigma_ratio);

}  // namespace heslam

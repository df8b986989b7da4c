// Motion-only bundle adjustment: refines one camera pose against fixed map points (ORB-SLAM2's
// Optimizer::PoseOptimization), with a Levenberg-Marquardt of its own on the 6-dof pose (motion_only_ba.cpp).
//
// Observations are monocular (u, v) or stereo (u, v, disparity), weighted by the keypoint's pyramid
// level; the disparity error has its own sigma, disparity_sigma_ratio x the keypoint's.
// Several rounds: optimize with a Huber kernel, classify every observation by its chi-square error
// (5.991 mono / 7.815 stereo, 95 %), optimize again on the inliers only; the last rounds drop the kernel.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"

namespace heslam {

struct PoseObservation {
  Eigen::Vector3d p_w;  // fixed map point, world frame
  double u_px = 0.0;
  double v_px = 0.0;
  double u_right_px = -1.0;  // < 0: monocular observation
  double inv_sigma2 = 1.0;   // 1 / (level scale)^2
  // The disparity's sigma is this many times the usual (disparity_sigma_ratio x the keypoint's): a
  // match near a clip edge (StereoFeatures::near_clip) is trusted less.
  double disparity_sigma_scale = 1.0;
  bool stereo() const { return u_right_px >= 0.0; }
};

struct MotionOnlyBaOptions {
  int rounds = 4;  // ORB-SLAM2: 4 optimizations of 10 iterations
  int iterations_per_round = 10;
  int robust_rounds = 2;       // rounds with the Huber kernel; later rounds are plain least squares
  double chi2_mono = 5.991;    // chi-square 95 % quantile, 2 dof
  double chi2_stereo = 7.815;  // chi-square 95 % quantile, 3 dof
  // Sigma of the disparity over the sigma of the keypoint position. Stereo disparity is refined to
  // subpixel by SAD, so it is more precise than the FAST corner: 0.5 measured best on EuRoC MH01
  // (docs/tracking.md); 1 with a u_right residual was ORB-SLAM2's choice.
  double disparity_sigma_ratio = 0.5;
};

struct MotionOnlyBaResult {
  Pose3 T_cw = Pose3::Identity();
  std::vector<bool> outlier;  // per observation
  int inliers = 0;
};

// Starts from T_cw_guess; returns the refined pose and the outlier flags of the last classification.
MotionOnlyBaResult optimize_pose(const PinholeStereo& camera, const std::vector<PoseObservation>& observations,
                                 const Pose3& T_cw_guess, const MotionOnlyBaOptions& options = {});

// Squared whitened residual of one observation at pose T_cw (the chi-square the rounds classify by);
// infinite when the point is behind the camera.
double observation_chi2(const PinholeStereo& camera, const PoseObservation& observation, const Pose3& T_cw,
                        double disparity_sigma_ratio);

}  // namespace heslam

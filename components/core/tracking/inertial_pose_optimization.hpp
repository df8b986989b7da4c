// Motion-only optimization with IMU factors (issue 34; ORB-SLAM3's PoseInertialOptimizationLastFrame):
// the current frame's body pose, velocity and biases against
//   - the reprojections of its matched map points (fixed), as motion_only_ba.hpp weighs them;
//   - the preintegrated IMU from the previous frame's state to this frame (an ImuFactor whose bias is
//     this frame's, as ORB-SLAM3 does);
//   - the bias random walk from the previous frame's biases;
//   - a prior on the previous frame's state: that state is held fixed and its uncertainty (prior_*) is
//     added to the IMU factor's covariance, which is what marginalizing a state with that Gaussian prior,
//     linked to nothing else, gives at first order (ImuIntervalResidual's extra_covariance).
// Rounds and outlier classification as optimize_pose(): Huber rounds then plain ones, every observation
// reclassified by its chi-square after each round. Solved by a Levenberg-Marquardt of its own on the 15x15
// normal equations (Ceres' defaults and damping, as motion_only_ba.cpp); optimize_pose_inertial_ceres() is
// the same cost solved with Ceres (a Problem per round, autodiff), kept as the reference the tests compare
// against (tests/tracking/test_inertial_pose_optimization.cpp).
//
// Frames: b is the IMU body, c the rectified left camera, T_cb the body in the camera (T_wc = T_wb T_cb^-1).
#pragma once

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/imu/preintegration.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/motion_only_ba.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

// The IMU's side of one frame's motion-only optimization: built by the inertial frontend
// (components/frontend/inertial_frontend.hpp) once the IMU is initialized.
struct InertialPoseConstraint {
  ImuPreintegration preintegration;  // from the previous frame to this one, around previous_bias
  NavState previous;                 // the previous frame's body state in the tracker's world
  ImuBias previous_bias;
  Eigen::Vector3d gravity_w = Eigen::Vector3d::Zero();
  Pose3 T_cb = Pose3::Identity();  // the body in the camera
  // Standard deviations of the previous state (its prior): rotation rad, position m, velocity m/s.
  double prior_rotation_rad = 1e-3;
  double prior_position_m = 1e-3;
  double prior_velocity_m_s = 1e-2;
};

// What the optimization found for the frame, besides its pose.
struct InertialFrameState {
  Eigen::Vector3d v_wb = Eigen::Vector3d::Zero();
  ImuBias bias;
};

struct InertialPoseResult {
  bool ok = false;  // false: the solver failed (non-finite); the caller keeps the visual optimization
  Pose3 T_cw = Pose3::Identity();
  InertialFrameState state;
  std::vector<bool> outlier;  // per observation
  int inliers = 0;
};

// Starts from T_cw_guess and, for the velocity, the previous state propagated by the preintegration.
InertialPoseResult optimize_pose_inertial(const PinholeStereo& camera, const std::vector<PoseObservation>& observations,
                                          const Pose3& T_cw_guess, const InertialPoseConstraint& constraint,
                                          const MotionOnlyBaOptions& options = {});

// The same cost, rounds and start solved with Ceres: the reference for optimize_pose_inertial() (about 30
// times slower; not used by the tracker).
InertialPoseResult optimize_pose_inertial_ceres(const PinholeStereo& camera,
                                                const std::vector<PoseObservation>& observations,
                                                const Pose3& T_cw_guess, const InertialPoseConstraint& constraint,
                                                const MotionOnlyBaOptions& options = {});

// optimize_frame_pose() with the IMU: the frame's matches as observations, the refined pose and the outlier
// flags written back; `state` receives the velocity and biases. Returns the number of inlier matches.
// Falls back to optimize_frame_pose() (state untouched) when the inertial solve fails.
int optimize_frame_pose_inertial(Frame& frame, const Map& map, const PinholeStereo& camera,
                                 const TrackerOptions& options, const InertialPoseConstraint& constraint,
                                 std::optional<InertialFrameState>& state);

}  // namespace heslam

// The frontend's inertial side without DDS: the IMU readings of imu/readings in an ImuBuffer, the IMU
// calibration with the camera's extrinsic, the preintegration between consecutive frames and between
// keyframes, the inertial initialization, and the pose prediction the tracker starts from (issue 34).
//
//   InertialFrontend inertial(options.inertial, "heslam/imu/readings");
//   inertial.set_imu_calibration(imu);  inertial.set_camera(rectifier.T_B_rect());
//   stream_reader.add(batch) -> inertial.buffer()
//   InertialFrontend::Prediction p = inertial.predict(stamp_ns);   // before tracking the frame
//   tracker.set_prediction(p.T_wc, p.fallback);
//   ... track ...
//   inertial.update(stamp_ns, result, tracker.local_map());          // after it
//
// Frames: the tracker's world is its first keyframe's rectified left camera; the IMU body b is the
// IMU sensor (T_BS of imu0), so T_cb = T_B_rect^-1 T_BS(imu). Gravity in that world comes from the
// initialization. Every decision depends on data stamps only (never a clock): lockstep runs repeat.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "components/core/geometry/pose.hpp"
#include "components/core/imu/imu_buffer.hpp"
#include "components/core/imu/preintegration.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/tracker.hpp"

namespace heslam::frontend {

// imu.* of the frontend config (docs/frontend.md, Inertial tracking).
struct InertialOptions {
  // imu.enabled / --imu auto|none: subscribe imu/readings + imu/calibration and use them. Off (the
  // default), the frontend is the stereo-only one, bit for bit.
  bool enabled = false;
  // imu.lockstep: before a frame with stamp t is tracked, wait until the IMU covers t (watermark), or
  // it ended, or imu.wait_s passed without it (then the IMU is declared dead: stereo-only, one
  // warning). Off (real time): never wait; a frame the IMU does not cover yet gets no prediction.
  bool lockstep = true;
  double wait_s = 5.0;
  // imu.init_min_duration_s / imu.init_min_keyframes: the inertial initialization is tried once the
  // keyframes since tracking started cover this long and are this many; imu.init_retry_s after a
  // failure it is tried again (with more keyframes), tracking stays stereo-only meanwhile.
  double init_min_duration_s = 1.0;
  int init_min_keyframes = 5;
  double init_retry_s = 0.5;
  // imu.init_max_keyframes: the newest keyframes the initialization uses.
  int init_max_keyframes = 30;
  // imu.init_max_gravity_stddev_deg / imu.init_max_accel_bias_stddev_m_s2: the initializer refuses an
  // estimate less certain than this (InertialInitOptions). Looser than its defaults so that the first
  // seconds of ordinary motion suffice: what a short prediction needs (gravity minus the accelerometer
  // bias along the current attitude) is well observed before the two are separated.
  double init_max_gravity_stddev_deg = 3.0;
  double init_max_accel_bias_stddev_m_s2 = 0.5;
  // imu.init_max_gravity_stddev_of_prior: the initializer's bound relative to what the accelerometer bias
  // prior alone leaves (InertialInitOptions::max_gravity_stddev_of_prior); 10: not binding.
  double init_max_gravity_stddev_of_prior = 10.0;
  // imu.refine_every_s / imu.refine_until_s: once initialized, the initialization runs again over the
  // newest keyframes this often, until this long after the first success; a more certain gravity
  // replaces the estimate (ORB-SLAM3 refines its initialization at 5 s and 15 s).
  double refine_every_s = 1.0;
  double refine_until_s = 15.0;
  // imu.blackout_max_s: how long after the last frame tracked by vision the IMU alone may give the
  // pose of frames vision cannot track (TrackingState::kInertialOnly); beyond it frames are lost.
  double blackout_max_s = 3.0;
  // imu.velocity_window_s: the velocity at a tracked frame comes from its pose and the pose of the
  // tracked frame about this long before it, with the preintegration between them.
  double velocity_window_s = 0.5;
  // imu.pose_optimization: once initialized, the tracker's local-map pose optimization of a frame that
  // follows a frame tracked by vision is the inertial one (components/core/tracking/
  // inertial_pose_optimization.hpp): pose, velocity and biases with the IMU factor from that frame, whose
  // velocity and biases the next frame starts from. Off: the visual optimization, the velocity from
  // velocity_window_s.
  bool pose_optimization = true;
  // imu.pose_optimization_max_gravity_stddev_deg: it waits for an estimate of gravity at least this certain
  // (the initializer's standard deviation; the estimate is refined every refine_every_s): the IMU factor takes
  // gravity as exact, and a tilt of d rad is an acceleration of 9.81 d m/s^2 it puts into every frame's motion
  // (0.5 deg: 4 mm/s of velocity a frame at 20 Hz, against a velocity prior of 30 mm/s).
  double pose_optimization_max_gravity_stddev_deg = 0.05;
  // imu.pose_prior_*: the standard deviations of the previous frame's state in that optimization.
  double pose_prior_rotation_rad = 1e-3;
  double pose_prior_position_m = 3e-3;
  double pose_prior_velocity_m_s = 3e-2;
};

enum class InertialInitState { kWaiting, kInitialized, kFailed, kOff };
const char* to_string(InertialInitState state);

// What the initialization found: gravity in the tracker's world, the biases, the velocity of the body at
// the last frame. (The initializer itself is components/core/imu/inertial_initialization.hpp.)
struct InertialEstimate {
  Eigen::Vector3d gravity_w = Eigen::Vector3d::Zero();
  ImuBias bias;
};

class InertialFrontend {
 public:
  InertialFrontend(const InertialOptions& options, const std::string& source);

  const InertialOptions& options() const { return options_; }
  ImuBuffer& buffer() { return buffer_; }
  const ImuBuffer& buffer() const { return buffer_; }

  void set_imu_calibration(const ImuCalibration& calibration);
  // The rectified left camera -> body transform (StereoRectifier::T_B_rect()).
  void set_camera(const Pose3& T_B_rect);
  bool has_calibration() const { return calibration_.has_value(); }
  bool has_camera() const { return T_B_rect_.has_value(); }
  // The IMU stamp of a camera stamp (the calibration's time offset).
  std::int64_t imu_stamp(std::int64_t camera_stamp_ns) const;

  // Off for good: the IMU stopped, its stream ended before the frames, or it never came (one warning
  // from the caller); tracking is stereo-only from then on.
  void turn_off(const std::string& reason);
  bool off() const { return state_ == InertialInitState::kOff; }
  InertialInitState state() const { return state_; }
  const std::string& reason() const { return reason_; }  // why failed / off (one line), else empty

  struct Prediction {
    std::optional<Pose3> T_wc;         // the tracker's starting pose for this frame
    std::optional<Pose3> fallback;     // the pose of the frame if vision cannot track it (blackout)
    std::optional<Eigen::Vector3d> v;  // the body's velocity with `fallback`
    // For Tracker::set_inertial_constraint (initialized, imu.pose_optimization, after a visual frame).
    std::optional<InertialPoseConstraint> constraint;
    ImuCoverage coverage = ImuCoverage::kPending;
    std::string message;  // why there is no prediction (the interval's), else empty
  };
  // Before tracking the frame at camera stamp stamp_ns: the IMU's prediction of its pose from the last
  // frame's. Gyro rotation with the constant-velocity translation before the initialization; the full
  // preintegrated prediction (velocity, gravity, biases) once initialized.
  Prediction predict(std::int64_t stamp_ns);

  // After tracking it: keeps the frame's pose, the keyframe it made, the velocity; tries the
  // initialization when due. Returns a line to log when the initialization state changed.
  std::optional<std::string> update(std::int64_t stamp_ns, const TrackResult& result, const Map& map);

  // A loop correction (or a merge) moved the tracker's last frame by T_corr (world side: T_wc after =
  // T_corr T_wc before): the recent frames' poses and velocities turn with it, so the next prediction
  // and the inertial pose optimization's prior on the previous state are in the corrected map.
  // Gravity stays: it belongs to the world, which the correction does not turn (a 4-DoF correction
  // turns about it; the global BA with IMU factors holds it).
  void moved(const Pose3& T_corr);

  // The body's velocity in the tracker's world at the last frame (initialized only).
  std::optional<Eigen::Vector3d> velocity() const;
  // The biases at the last frame: its inertial pose optimization's, else the initialization's.
  std::optional<ImuBias> bias() const;
  std::uint64_t pose_optimizations() const { return pose_optimizations_; }
  const std::optional<InertialEstimate>& estimate() const { return estimate_; }
  std::uint64_t init_attempts() const { return init_attempts_; }
  std::uint64_t predictions() const { return predictions_; }
  std::uint64_t gaps() const { return gaps_; }
  std::uint64_t refinements() const { return refinements_; }

 private:
  struct FrameState {
    std::int64_t stamp_ns = 0;  // IMU time
    Pose3 T_wb = Pose3::Identity();
    bool visual = false;  // tracked by vision (not inertial-only)
    std::optional<Eigen::Vector3d> v_wb;
    std::optional<ImuBias> bias;  // of its inertial pose optimization; else the estimate's
  };
  ImuBias bias_at(const FrameState& frame) const { return frame.bias ? *frame.bias : estimate_->bias; }
  Pose3 body_pose(const Pose3& T_wc) const { return T_wc * *T_cb_; }
  Pose3 camera_pose(const Pose3& T_wb) const { return T_wb * T_cb_->inverse(); }
  std::optional<ImuPreintegration> preintegrate_between(std::int64_t t0_ns, std::int64_t t1_ns);
  std::optional<std::string> try_initialize(std::int64_t stamp_ns, const Map& map);
  void estimate_velocity(FrameState& current);

  InertialOptions options_;
  ImuBuffer buffer_;
  std::optional<ImuCalibration> calibration_;
  void update_extrinsic();
  std::optional<Pose3> T_B_rect_;  // the rectified left camera -> body
  std::optional<Pose3> T_cb_;      // IMU (the inertial body b) -> rectified left camera, once both are known
  InertialInitState state_ = InertialInitState::kWaiting;
  std::string reason_;
  std::optional<InertialEstimate> estimate_;
  std::deque<FrameState> frames_;  // the recent frames with a pose, oldest first
  std::optional<std::int64_t> last_visual_ns_;
  std::optional<Eigen::Vector3d> predicted_v_;  // of the last prediction (initialized)
  std::optional<std::int64_t> first_keyframe_ns_;
  std::optional<std::int64_t> next_init_ns_;
  std::optional<std::int64_t> initialized_ns_;
  double gravity_stddev_deg_ = 0.0;  // of the estimate in use
  std::uint64_t refinements_ = 0;
  std::uint64_t init_attempts_ = 0;
  std::uint64_t predictions_ = 0;
  std::uint64_t gaps_ = 0;
  std::uint64_t pose_optimizations_ = 0;
};

}  // namespace heslam::frontend

// The local mapper's inertial side without DDS (issue 34): the IMU readings in an ImuBuffer, the IMU
// calibration with the camera's extrinsic, the mapper's own inertial initialization over its keyframes
// (ORB-SLAM3 initializes in the mapper too), a velocity and biases per keyframe, and the inertial local
// BA (inertial_bundle_adjustment.hpp) that replaces the visual one once initialized.
//
//   InertialMapping inertial(options.inertial, "heslam/imu/readings");
//   inertial.set_imu_calibration(imu);  inertial.set_camera(T_B_rect);
//   stream_reader.add(batch) -> inertial.buffer()
//   mapper.set_bundle_adjustment([&](...) { return inertial.bundle_adjust(...); });
//
// Before initialization, or when the IMU cannot cover the keyframes (a gap, a dead IMU, readings
// missing), bundle_adjust returns nothing and the mapper runs the visual BA: a fallback counted and
// warned about once per kind. Every decision depends on data stamps only (lockstep runs repeat).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/imu/imu_buffer.hpp"
#include "components/core/imu/inertial_initialization.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/inertial_bundle_adjustment.hpp"
#include "components/core/mapping/local_bundle_adjustment.hpp"
#include "components/core/mapping/map_changes.hpp"

namespace heslam {

// imu.* of the local mapper config (docs/local_mapper.md, Inertial local BA).
struct InertialMappingOptions {
  // imu.enabled / --imu auto|none: subscribe imu/readings + imu/calibration + calibration and run the
  // inertial local BA. Off (the default): the visual BA, bit for bit.
  bool enabled = false;
  // imu.wait_s: lockstep only (the process's real_time off): before a keyframe is mapped, wait up to this
  // long for the IMU to cover its stamp; then the IMU is declared off (visual BA, one warning).
  double wait_s = 5.0;
  // imu.window_keyframes: the newest keyframes in time order with a velocity and biases in the local BA
  // (ORB-SLAM3: 10), plus the one before them, held fixed.
  int window_keyframes = 10;
  // imu.estimate_gravity: the local BA estimates the direction of gravity too, with the initialization's
  // stddev as its prior (ORB-SLAM3 refines it in its inertial BAs of the initialization). False: held.
  bool estimate_gravity = true;
  // imu.init_min_keyframes / imu.init_min_duration_s / imu.init_max_keyframes: the initialization is tried
  // at each keyframe once the map's newest keyframes (at most init_max_keyframes) are this many over
  // this long; until it succeeds the visual BA runs. imu.init_max_gravity_stddev_deg,
  // imu.init_max_accel_bias_stddev_m_s2, imu.init_max_gravity_stddev_of_prior: the initializer's refusal
  // thresholds (InertialInitOptions), the frontend's values (config/frontend/inertial.yaml).
  int init_min_keyframes = 5;
  double init_min_duration_s = 1.0;
  int init_max_keyframes = 30;
  // imu.refine_every_s / imu.refine_until_s: once initialized, the initialization runs again over the
  // newest keyframes (refined by the inertial BA) this often until this long after the first success;
  // a more certain gravity replaces the estimate (ORB-SLAM3 refines at 5 s and 15 s).
  double refine_every_s = 1.0;
  double refine_until_s = 15.0;
  // min_duration_s / min_intervals follow init_min_*; the rest as InertialInitOptions, with the
  // refusal thresholds above.
  InertialInitOptions init = [] {
    InertialInitOptions o;
    o.max_gravity_stddev_deg = 3.0;
    o.max_accel_bias_stddev_m_s2 = 0.5;
    o.max_gravity_stddev_of_prior = 10.0;
    return o;
  }();
  ImuBufferOptions buffer;
};

// What happened so far (counters on the status topic).
struct InertialMappingCounts {
  std::uint64_t inertial_bas = 0;      // local BAs with IMU factors
  std::uint64_t visual_fallbacks = 0;  // keyframes after initialization mapped with the visual BA (bad IMU)
  std::uint64_t failed_solves = 0;     // inertial BAs that gave nothing usable (then visual)
  std::uint64_t init_attempts = 0;
  std::uint64_t refinements = 0;
  std::uint64_t initialized = 0;  // 1 once initialized
  std::uint64_t imu_factors = 0;
};

class InertialMapping {
 public:
  using Warn = std::function<void(const std::string&)>;

  InertialMapping(const InertialMappingOptions& options, const std::string& source);

  ImuBuffer& buffer() { return buffer_; }
  const ImuBuffer& buffer() const { return buffer_; }
  void set_imu_calibration(const ImuCalibration& calibration);
  // The rectified left camera -> body transform (StereoRectifier::T_B_rect()).
  void set_camera(const Pose3& T_B_rect);
  bool has_calibration() const { return calibration_.has_value(); }
  bool has_camera() const { return T_cb_.has_value(); }
  // The IMU stamp of a camera stamp (the calibration's time offset).
  std::int64_t imu_stamp(std::int64_t camera_stamp_ns) const;

  // The IMU is not used any more (it stopped, never came): the visual BA from now on.
  void turn_off(const std::string& reason);
  bool off() const { return off_; }
  bool initialized() const { return initialized_; }
  const Eigen::Vector3d& gravity_w() const { return gravity_w_; }
  const std::map<KeyframeId, InertialKeyframeState>& states() const { return states_; }
  const InertialMappingCounts& counts() const { return counts_; }
  // Warnings (a fallback to the visual BA, a failed initialization, the IMU off): one per kind, then
  // counted only; info: the initialization's result.
  void set_log(Warn warn, Warn info) {
    warn_ = std::move(warn);
    info_ = std::move(info);
  }

  // The local BA of keyframe kf_id with IMU factors, or nothing (not initialized, IMU unusable: the
  // caller runs the visual BA). Tries the initialization first when not yet initialized.
  std::optional<LocalBundleAdjustmentResult> bundle_adjust(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                           const LocalBundleAdjustmentOptions& options,
                                                           MapChanges& changes);

  // Keyframes moved rigidly (a loop correction): their velocities turn with them (old_T_wc: the poses
  // before, map: after).
  void moved(const std::map<KeyframeId, Pose3>& old_T_wc, const Map& map);

 private:
  // Tries (or refines) the initialization over the map's newest keyframes up to IMU stamp t; true when
  // it succeeded (and, refining, gave a more certain gravity).
  bool try_initialize(const Map& map, std::int64_t t);
  // The preintegration between two keyframe stamps (IMU time) around `bias`, or the reason it cannot be had.
  std::optional<ImuPreintegration> interval(std::int64_t t0, std::int64_t t1, const ImuBias& bias,
                                            std::string& why) const;
  void warn_once(const std::string& kind, const std::string& message);

  InertialMappingOptions options_;
  ImuBuffer buffer_;
  std::optional<ImuCalibration> calibration_;
  std::optional<Pose3> T_B_rect_;
  std::optional<Pose3> T_cb_;  // IMU -> rectified left camera
  bool off_ = false;
  bool initialized_ = false;
  Eigen::Vector3d gravity_w_ = Eigen::Vector3d::Zero();
  std::map<KeyframeId, InertialKeyframeState> states_;
  std::set<KeyframeId> seeded_;       // states guessed after a gap (not held as a chain's anchor)
  std::optional<ImuBias> last_bias_;  // the newest keyframe's
  InertialMappingCounts counts_;
  std::set<std::string> warned_;
  double gravity_stddev_deg_ = 0.0;
  std::optional<std::int64_t> initialized_ns_;
  std::int64_t next_refine_ns_ = 0;
  Warn warn_;
  Warn info_;
};

}  // namespace heslam

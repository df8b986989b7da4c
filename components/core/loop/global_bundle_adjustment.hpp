// Full bundle adjustment after a loop closure (ORB-SLAM2's RunGlobalBundleAdjustment): every live
// keyframe and every live point they observe, stereo (u, v, u_right) and mono (u, v) reprojection
// terms whitened by the keypoint's level (the local BA's terms, bundle_adjustment_terms.hpp) under a
// Huber kernel at the chi2 95 % thresholds, the oldest keyframe fixed.
//
// Inertial runs (issue 34): with a GlobalInertialInput it also holds, per keyframe of the input's IMU
// chain, the body's velocity and the gyroscope and accelerometer biases, and between consecutive
// keyframes (time order) the IMU factor of the mapper's inertial local BA (ImuCameraCost: the
// preintegration between their stamps on the BA's camera pose blocks through the IMU-camera extrinsic)
// and the bias random walk; gravity is held (the odometry's, the one of the 4-DoF pose graph), and a
// weak prior on the biases of each chain's first keyframe keeps a short chain well posed. Without it
// the problem is the visual one, bit for bit. global_inertial_chain.hpp builds the input from IMU readings.
//
// Works on a read-only map and returns new poses and positions; the loop closer publishes the poses
// as a LoopCorrection. A `stop` flag, checked after every solver iteration, aborts it (a new loop
// was detected, or shutdown): the state reached so far is returned with `aborted` set.
#pragma once

#include <atomic>
#include <map>
#include <utility>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/imu/preintegration.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/inertial_bundle_adjustment.hpp"

namespace heslam {

struct GlobalBundleAdjustmentOptions {
  int max_iterations = 10;   // ORB-SLAM2's global BA after a loop: 10 iterations
  double mono_chi2 = 5.991;  // Huber thresholds: 2- and 3-dof chi2 at 95 %
  double stereo_chi2 = 7.815;
  double disparity_sigma_ratio = 0.5;  // as LocalBundleAdjustmentOptions (the same measurement model)
  int num_threads = 1;                 // the machine is shared with the other processes
};

// The IMU between two keyframes consecutive in time: preintegrated between their stamps (IMU time)
// around the bias of `from`'s initial state.
struct GlobalInertialInterval {
  KeyframeId from = kNoId;
  KeyframeId to = kNoId;
  ImuPreintegration preintegration;
};

struct GlobalInertialInput {
  Pose3 T_cb = Pose3::Identity();                                // IMU body -> rectified left camera
  Eigen::Vector3d gravity_w = Eigen::Vector3d(0.0, 0.0, -9.81);  // in the map's world, held
  // In time order; a chain breaks where two consecutive keyframes have no interval (an IMU gap, the
  // buffer's start, another map).
  std::vector<GlobalInertialInterval> intervals;
  // The initial velocity and biases of every keyframe of an interval.
  std::map<KeyframeId, InertialKeyframeState> states;
  // Prior on the biases of each chain's first keyframe around its initial biases (the initializer's
  // default stddevs): without it a chain of two keyframes leaves the biases free.
  double gyro_bias_prior_stddev_rad_s = 0.1;
  double accel_bias_prior_stddev_m_s2 = 0.2;
};

struct GlobalBundleAdjustmentStats {
  int keyframes = 0;  // optimized, the fixed one included
  int points = 0;
  int observations = 0;
  int iterations = 0;
  int imu_factors = 0;            // IMU factors in the problem (0: visual only)
  int inertial_keyframes = 0;     // keyframes with a velocity and biases
  int imu_intervals_skipped = 0;  // input intervals left out (a keyframe culled or not in the problem)
  bool aborted = false;
  double initial_cost = 0.0;  // Ceres cost (robustified, 1/2 sum of squares) before and after
  double final_cost = 0.0;
  double time_ms = 0.0;
};

struct GlobalBundleAdjustmentResult {
  std::vector<std::pair<KeyframeId, Pose3>> corrected_T_wc;  // every live keyframe, id order
  std::vector<std::pair<PointId, Eigen::Vector3d>> p_w;      // every optimized point, id order
  std::map<KeyframeId, InertialKeyframeState> states;        // with an inertial input: the optimized states
  GlobalBundleAdjustmentStats stats;
};

class GlobalBundleAdjustment {
 public:
  explicit GlobalBundleAdjustment(const GlobalBundleAdjustmentOptions& options = {}) : options_(options) {}

  // `inertial`: the IMU factors of an inertial run (nullptr: visual only). Throws std::invalid_argument
  // when an interval's keyframe has no state in it.
  GlobalBundleAdjustmentResult compute(const Map& map, const PinholeStereo& camera,
                                       const std::atomic<bool>* stop = nullptr,
                                       const GlobalInertialInput* inertial = nullptr) const;

 private:
  GlobalBundleAdjustmentOptions options_;
};

}  // namespace heslam

// Full bundle adjustment after a loop closure (ORB-SLAM2's RunGlobalBundleAdjustment): every live
// keyframe and every live point they observe, stereo (u, v, u_right) and mono (u, v) reprojection
// terms whitened by the keypoint's level (the local BA's terms, bundle_adjustment_terms.hpp) under a
// Huber kernel at the chi2 95 % thresholds, the oldest keyframe fixed.
//
// Works on a read-only map and returns new poses and positions; the loop closer publishes the poses
// as a LoopCorrection. A `stop` flag, checked after every solver iteration, aborts it (a new loop
// was detected, or shutdown): the state reached so far is returned with `aborted` set.
#pragma once

#include <atomic>
#include <utility>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"

namespace heslam {

struct GlobalBundleAdjustmentOptions {
  int max_iterations = 10;   // ORB-SLAM2's global BA after a loop: 10 iterations
  double mono_chi2 = 5.991;  // Huber thresholds: 2- and 3-dof chi2 at 95 %
  double stereo_chi2 = 7.815;
  double disparity_sigma_ratio = 0.5;  // as LocalBundleAdjustmentOptions (the same measurement model)
  int num_threads = 1;                 // the machine is shared with the other processes
};

struct GlobalBundleAdjustmentStats {
  int keyframes = 0;  // optimized, the fixed one included
  int points = 0;
  int observations = 0;
  int iterations = 0;
  bool aborted = false;
  double initial_cost = 0.0;  // Ceres cost (robustified, 1/2 sum of squares) before and after
  double final_cost = 0.0;
  double time_ms = 0.0;
};

struct GlobalBundleAdjustmentResult {
  std::vector<std::pair<KeyframeId, Pose3>> corrected_T_wc;  // every live keyframe, id order
  std::vector<std::pair<PointId, Eigen::Vector3d>> p_w;      // every optimized point, id order
  GlobalBundleAdjustmentStats stats;
};

class GlobalBundleAdjustment {
 public:
  explicit GlobalBundleAdjustment(const GlobalBundleAdjustmentOptions& options = {}) : options_(options) {}

  GlobalBundleAdjustmentResult compute(const Map& map, const PinholeStereo& camera,
                                       const std::atomic<bool>* stop = nullptr) const;

 private:
  GlobalBundleAdjustmentOptions options_;
};

}  // namespace heslam

// Local bundle adjustment (ORB-SLAM2's Optimizer::LocalBundleAdjustment) with its own solver
// (bundle_adjustment_solver.hpp).
//
// Free: the keyframe and its covisible keyframes, and every point they observe. Fixed: the other
// keyframes observing those points (they anchor the gauge), and the map's first keyframe. Residuals
// are pixel errors (u, v) or (u, v, u_right) for keypoints with stereo depth, whitened by the
// keypoint's pyramid level, under a Huber kernel at the chi2 95 % threshold. After the first pass,
// observations above the threshold are dropped and a second pass runs on the rest (same problem,
// kernel kept: its inliers start in the quadratic region); outliers left at the end are unlinked.
#pragma once

#include <set>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/local_mapper_options.hpp"
#include "components/core/mapping/map_changes.hpp"

namespace heslam {

struct LocalBundleAdjustmentResult {
  int free_keyframes = 0;
  int fixed_keyframes = 0;
  int points = 0;
  int observations = 0;
  int outliers_removed = 0;     // observations unlinked after the second pass
  bool aborted = false;         // stop_requested stopped it; the state reached so far is kept
  double initial_rms_px = 0.0;  // RMS of the whitened residual over all observations, before
  double final_rms_px = 0.0;    // ... and after, over the inliers
};

// Runs on `map` in place: moved keyframes / points and removed points are recorded in `changes`.
LocalBundleAdjustmentResult local_bundle_adjustment(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                    const LocalBundleAdjustmentOptions& options, MapChanges& changes);

}  // namespace heslam

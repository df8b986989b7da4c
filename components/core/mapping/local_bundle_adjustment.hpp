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

#include <map>
#include <set>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/bundle_adjustment_solver.hpp"
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

// The local BA's window and its solve, shared by the visual BA (below) and the inertial one
// (inertial_bundle_adjustment.hpp): which keyframes are free and fixed, the points and observations in
// the problem, the two passes, the write-back and the unlinking of the outliers left.
class LocalBundleAdjustmentWindow {
 public:
  // Free: kf_id, its covisible keyframes and `more_free`, less `more_fixed` and the map's origin;
  // fixed: the other observers of their points, `more_fixed` and the origin (when nothing is fixed, the
  // oldest free keyframe). kf_id missing or culled: an empty window (valid() false).
  LocalBundleAdjustmentWindow(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                              const LocalBundleAdjustmentOptions& options,
                              const std::vector<KeyframeId>& more_free = {},
                              const std::set<KeyframeId>& more_fixed = {});

  bool valid() const { return valid_; }
  // Something to solve: free keyframes and observations.
  bool solvable() const { return valid_ && !free_kfs_.empty() && !observations_.empty(); }
  const std::set<KeyframeId>& free_keyframes() const { return free_kfs_; }
  // The problem's pose of a keyframe of the window (free or fixed).
  std::size_t pose_index(KeyframeId id) const { return pose_index_.at(id); }
  BundleAdjustmentProblem& problem() { return problem_; }
  // The figures so far (counts and initial RMS once built; the rest after solve and write_back).
  LocalBundleAdjustmentResult& result() { return result_; }

  // ORB-SLAM2's two passes (options' iterations; a stop request during the first skips the second),
  // with `extra` terms in both (may be nullptr). True when options.stop_requested ended it.
  bool solve(BundleAdjustmentExtraTerms* extra);
  // The solver's cost before the first pass and after the last (0.5 sum of rho; with the extra terms).
  double initial_cost() const { return initial_cost_; }
  double final_cost() const { return final_cost_; }
  // All free poses and points finite.
  bool finite() const;
  // Writes the free poses and the points back, unlinks the outliers left (and points too weakly observed
  // after it), records everything in `changes`.
  void write_back(MapChanges& changes);

 private:
  struct Observation {
    KeyframeId kf_id;
    int index;
    PointId point_id;
    bool stereo;
    double chi2_threshold;
    std::size_t pose = 0;   // index into the problem's poses
    std::size_t point = 0;  // ... and points
    double u_px = 0.0;
    double v_px = 0.0;
    double disparity_px = 0.0;  // u - u_right (computed in float, as the keypoints are)
    double inv_sigma2 = 0.0;    // of the keypoint's pyramid level
    bool inlier = true;
  };
  bool chi2_of(const Observation& obs, double& chi2) const;
  double rms() const;

  Map& map_;
  const PinholeStereo& camera_;
  const LocalBundleAdjustmentOptions& options_;
  bool valid_ = false;
  std::set<KeyframeId> free_kfs_;
  std::set<KeyframeId> fixed_kfs_;
  std::map<KeyframeId, std::size_t> pose_index_;
  std::map<PointId, std::size_t> point_index_;
  std::vector<Observation> observations_;
  BundleAdjustmentProblem problem_;
  LocalBundleAdjustmentResult result_;
  double initial_cost_ = 0.0;
  double final_cost_ = 0.0;
};

// Runs on `map` in place: moved keyframes / points and removed points are recorded in `changes`.
LocalBundleAdjustmentResult local_bundle_adjustment(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                    const LocalBundleAdjustmentOptions& options, MapChanges& changes);

}  // namespace heslam

// The loop closer's core (ORB-SLAM2 LoopClosing without threads or I/O): per new keyframe, detect
// candidates (a swappable LoopDetector), verify each geometrically (BoW / projection matches, SE(3)
// RANSAC, refinement, projection top-up) and turn an accepted loop into a LoopCorrection (propagated
// group, fused points, essential-graph optimization); optionally a global bundle adjustment after it.
// Works on a read-only Map (the loop closer's mirror of the local mapper's map); deterministic.
#pragma once

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/loop/global_bundle_adjustment.hpp"
#include "components/core/loop/loop_correction_builder.hpp"
#include "components/core/loop/loop_detector.hpp"
#include "components/core/loop/map_merge.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/loop_correction.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

struct LoopClosingOptions {
  // Matches of a candidate before RANSAC (ORB-SLAM2 ComputeSim3: 20 BoW matches).
  int min_candidate_matches = 20;
  // RANSAC inliers after refinement (ORB-SLAM2: 20), then all matches after the projection top-up
  // over the candidate's covisible group (ORB-SLAM2: 40): below either the candidate is rejected.
  int min_ransac_inliers = 20;
  int min_loop_matches = 40;
  float projection_radius_px = 10.f;  // ORB-SLAM2 SearchByProjection in ComputeSim3
  // Drift gate. A verified loop says how far the odometry drifted since the matched keyframe: the loop
  // keyframe would move from its estimate to matched.T_wc * T_matched_loop. Stereo odometry drifts
  // about 1 % of the path and 0.3-1 deg per 100 m (KITTI), so a loop that needs far more is a look-alike
  // place (perceptual aliasing: the same facades on another street) and is rejected. Allowed:
  // max_drift_fraction * path + min_drift_allowance_m of translation and max_rotation_drift_deg_per_m *
  // path + min_rotation_allowance_deg of rotation, path = the distance travelled between the two
  // keyframes. The rotation bound is loose (handheld odometry turns fast); it only catches gross
  // aliasing such as a place seen the other way round. ORB-SLAM2 has no such gate (its monocular scale
  // drift makes one hard); stereo can.
  double max_drift_fraction = 0.1;
  double min_drift_allowance_m = 1.0;
  double max_rotation_drift_deg_per_m = 0.2;
  double min_rotation_allowance_deg = 10.0;
  std::uint64_t ransac_seed = 0x100b;
  // The atlas: look for places of other maps too and merge them (map_merge.hpp).
  bool merging = true;
  MapMergeOptions merge;                    // its `correction` is replaced by the loops' `correction` below
  TrackerOptions matching;                  // descriptor thresholds, orientation check
  LoopCorrectionBuilderOptions correction;  // pose_graph.* (4-DoF in inertial runs)
};

struct LoopRejection {
  KeyframeId candidate = kNoId;
  std::string reason;  // e.g. "12 BoW matches (< 20)"
};

struct LoopClosingTimings {
  double detection_ms = 0.0;
  double verification_ms = 0.0;  // matching + RANSAC + refinement + top-up, all candidates
  double correction_ms = 0.0;    // group propagation, fusion, essential graph
  double merge_ms = 0.0;         // a merge's weld (map_merge.hpp)
};

// A place verified geometrically (a loop, or a merge with another map) before any correction.
struct VerifiedPlace {
  Pose3 T_matched_loop = Pose3::Identity();                 // the query keyframe in the candidate's frame
  std::vector<std::pair<PointId, PointId>> matched_points;  // (query-side, candidate-side) RANSAC inliers
  int matches = 0;                                          // after the projection top-up
};

struct LoopClosingResult {
  LoopCandidates candidates;
  std::vector<LoopRejection> rejected;
  std::optional<LoopCorrection> correction;  // id 0: the caller assigns it; kind kMerge for a merge
  int loop_matches = 0;
  MapId merged_map = kFirstMapId;  // a merge: the map welded into ...
  MapId into_map = kFirstMapId;    // ... this one
  MapMergeStats merge_stats;
  std::string merge_found;  // a merge: the points predicted in view found (LoopClosing::found_share_too_low)
  LoopClosingTimings timings;
};

class LoopClosing {
 public:
  LoopClosing(const PinholeStereo& camera, std::unique_ptr<LoopDetector> detector, const LoopClosingOptions& options);
  ~LoopClosing();

  // Processes keyframe `query` of `map`. On an accepted loop the result holds the correction
  // (corrected poses of every keyframe, point merges) computed on map.version.
  LoopClosingResult process_keyframe(const Map& map, KeyframeId query);

  // The atlas: places of maps other than `query`'s (LoopDetector::detect_merge), verified without the
  // drift gate, merged with the merge gate (map_merge.hpp). On an accepted merge the correction (kind
  // kMerge) moves the newer of the two maps into the older (usually the query's into the matched
  // keyframe's; the other way when the query's map is the older: another agent's newer map, a map
  // relocalized back into); the caller publishes it as a loop's.
  LoopClosingResult process_merge(const Map& map, KeyframeId query);

  // The shared geometric check of candidate `candidate` for keyframe `query`: the detector's matches,
  // SE(3) RANSAC, the projection top-up; with `drift_gate` also the drift gate. nullopt with the
  // reason in `why` when rejected. A merge calls it without the drift gate (two maps' poses are not
  // comparable) and applies its own gate (map_merge.hpp).
  std::optional<VerifiedPlace> verify_place(const Map& map, KeyframeId query, KeyframeId candidate, bool drift_gate,
                                            std::string& why) const;
  // A verified merge the detector did not confirm: empty when enough of `query`'s covisible keyframes see
  // the candidate's covisible group where T_matched_query places them (MapMergeOptions), else why not.
  std::string confirm_in_space(const Map& map, const Keyframe& query, KeyframeId candidate,
                               const Pose3& T_matched_query) const;
  // A verified merge at a look-alike place: true when, of the points the candidate's covisible group puts
  // in the query's view and the query's group in the candidate's (placed by T_matched_query), fewer than
  // MapMergeOptions::min_found_share are found there; `figures` says how many were.
  bool found_share_too_low(const Map& map, const Keyframe& query, KeyframeId candidate, const Pose3& T_matched_query,
                           std::string& figures) const;

  // A global bundle adjustment of the whole map, as a correction of kind kGlobalBundleAdjustment
  // (poses and point positions). nullopt when `abort` was set before it finished. `inertial`: the IMU
  // factors of an inertial run (global_inertial_chain.hpp); `stats` receives the solver's figures.
  std::optional<LoopCorrection> global_bundle_adjustment(const Map& map, const std::atomic<bool>* abort,
                                                         const GlobalInertialInput* inertial = nullptr,
                                                         GlobalBundleAdjustmentStats* stats = nullptr) const;

  const LoopDetector& detector() const { return *detector_; }
  // Accepted loops (loop keyframe, matched keyframe): the essential graph keeps them as edges. A
  // restarted loop closer restores them.
  const std::vector<std::pair<KeyframeId, KeyframeId>>& loop_edges() const { return loop_edges_; }
  void add_loop_edge(KeyframeId loop_kf, KeyframeId matched_kf) { loop_edges_.emplace_back(loop_kf, matched_kf); }
  // Inertial runs: from now on loop corrections use the 4-DoF pose graph about gravity_w (gravity's
  // direction in the map's world, any length), as options.correction.pose_graph.four_dof / gravity_w do.
  void use_four_dof_pose_graph(const Eigen::Vector3d& gravity_w) {
    options_.correction.pose_graph.four_dof = true;
    options_.correction.pose_graph.gravity_w = gravity_w;
  }
  const PoseGraphOptions& pose_graph_options() const { return options_.correction.pose_graph; }

 private:
  PinholeStereo camera_;
  std::unique_ptr<LoopDetector> detector_;
  LoopClosingOptions options_;
  std::vector<std::pair<KeyframeId, KeyframeId>> loop_edges_;  // accepted loops: the essential graph keeps them
};

}  // namespace heslam

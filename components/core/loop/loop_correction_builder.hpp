// The loop correction for a verified loop (ORB-SLAM2's LoopClosing::CorrectLoop, SE(3) for stereo),
// computed as a pure function of a read-only map:
//   (a) the loop keyframe takes T_wc(matched) T_matched_loop; its covisible group moves rigidly with it;
//   (b) the group's map points move with the group (returned, for the loop closer's own use);
//   (c) duplicates: the matched keyframe's group's points are projected into the corrected loop group;
//       a keypoint already holding a loop-side point with a descriptor within TH_LOW makes a merge
//       (loop-side point -> matched-side point, the older point survives as in ORB-SLAM2);
//   (d) the loop connections (new covisibility after the merges) and the essential graph are
//       optimized with the matched keyframe fixed;
//   (e) the result is a LoopCorrection with every live keyframe's new pose and the merges.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/loop/essential_graph.hpp"
#include "components/core/loop/pose_graph.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/loop_correction.hpp"

namespace heslam {

// A loop verified by the loop closer (BoW candidate + Se3Ransac).
struct LoopCandidate {
  KeyframeId loop_kf = kNoId;     // the current keyframe
  KeyframeId matched_kf = kNoId;  // the old keyframe it matched
  Pose3 T_matched_loop = Pose3::Identity();
  // Optional (loop-side point, matched-side point) pairs already known to be the same point (the
  // RANSAC inliers); merged before the projection search (ORB-SLAM2's mvpCurrentMatchedPoints).
  std::vector<std::pair<PointId, PointId>> matched_points;
};

struct LoopCorrectionBuilderOptions {
  int max_descriptor_distance = 50;  // ORB-SLAM2 TH_LOW
  float fuse_radius_px = 4.f;        // ORB-SLAM2 SearchAndFuse: 4 px x the predicted level's scale
  double min_view_cos = 0.5;         // viewing direction within 60 deg of the point's mean
  // ORB-SLAM2 fixes only the matched keyframe; true also holds the corrected loop group (the
  // verified transform then is not spread into the loop side).
  bool fix_loop_group = false;
  EssentialGraphOptions essential_graph;
  // pose_graph.four_dof (inertial runs): the essential graph moves keyframes only in yaw about
  // pose_graph.gravity_w and in translation, and the loop group's rigid correction (a) is reduced to
  // its yaw part too, so no keyframe's roll or pitch changes.
  PoseGraphOptions pose_graph;
};

struct LoopCorrectionStats {
  int loop_group_keyframes = 0;     // loop keyframe + its covisible keyframes
  int matched_group_keyframes = 0;  // matched keyframe + its covisible keyframes
  int loop_group_points = 0;
  int matched_group_points = 0;
  int point_merges = 0;
  int unlinked_matches = 0;    // projections onto a free keypoint (ORB-SLAM2 would add an observation)
  int loop_connections = 0;    // keyframe pairs newly covisible through the merges
  EssentialGraph graph_edges;  // edge counts (edges themselves cleared)
  PoseGraphStats pose_graph;
  double fusion_ms = 0.0;
  double total_ms = 0.0;
};

struct LoopCorrectionOutput {
  std::string error;                                  // empty on success; else what was wrong with the input
  LoopCorrection correction;                          // id 0: the loop closer numbers its corrections
  std::map<PointId, Eigen::Vector3d> loop_group_p_w;  // (b): the group's points after the rigid correction
  LoopCorrectionStats stats;
};

class LoopCorrectionBuilder {
 public:
  explicit LoopCorrectionBuilder(const LoopCorrectionBuilderOptions& options = {}) : options_(options) {}

  // `previous_loop_edges`: keyframe pairs of the loops closed before (they stay in the graph).
  LoopCorrectionOutput compute(const Map& map, const PinholeStereo& camera, const LoopCandidate& loop,
                               const std::vector<std::pair<KeyframeId, KeyframeId>>& previous_loop_edges) const;

 private:
  LoopCorrectionBuilderOptions options_;
};

}  // namespace heslam

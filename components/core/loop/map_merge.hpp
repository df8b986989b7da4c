// Map merging (ORB-SLAM3's Atlas MergeLocal for stereo, SE(3)): the active map A and an older map B
// showing one place are welded into one map in B's frame, computed as a pure function of a read-only
// map store (the loop closer's mirror); the result is a LoopCorrection the mapper applies as it
// applies a loop correction.
//
// Which map moves: A, the active (newer) map, into B's frame. B's poses are what the trajectory files
// and the frontend's earlier output already hold; A is usually the smaller one (it was started after
// a loss); and the frontend follows A's motion through its odometry-to-map transform T_wo exactly as
// it follows a loop correction, so its odometry does not jump (components/frontend).
//
// Steps, on a private copy of maps A and B (other maps take no part and are not moved):
//   (a) A moves rigidly by T_BA = T_wc(matched) T_matched_active T_wc(active)^-1, keyframes and points;
//   (b) the seam: duplicates of B's seam group in A's seam group are fused (A's point is replaced by
//       B's, the older survives), the new covisibility joins the two maps, and the essential graph of
//       the union is optimized with B's matched keyframe fixed (loop_correction_builder.hpp);
//   (c) a local bundle adjustment around the seam (the active keyframe and its covisible keyframes,
//       which now include B's) welds the two maps on their shared points;
//   (d) the result lists every live keyframe of A and B with its new pose, the seam BA's point
//       positions and the point merges.
#pragma once

#include <set>
#include <string>
#include <utility>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/loop/loop_correction_builder.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/local_bundle_adjustment.hpp"
#include "components/core/mapping/loop_correction.hpp"

namespace heslam {

struct MapMergeOptions {
  // Merge gate (the loop's drift gate has no meaning across maps: their frames are unrelated). When A
  // was started after B's last keyframe by the same camera (its first keyframe is newer), the camera
  // went from B's last keyframe to A's first one unobserved: the merge places them
  // max_unobserved_speed_mps x the time between them apart at most, plus the odometry drift of both
  // maps between the seam and those keyframes (max_drift_fraction x path + min_drift_allowance_m, as
  // the drift gate). 0 = no speed bound (multi-session, or a synthetic teleport). Maps that overlap in
  // time (another agent) have no such bound.
  double max_unobserved_speed_mps = 10.0;  // a car in town, a running person: 36 km/h
  double max_drift_fraction = 0.1;         // as LoopClosingOptions
  double min_drift_allowance_m = 1.0;
  // With pose_graph.four_dof (inertial: both maps gravity-aligned) the relative rotation may only turn
  // about gravity: a tilt above this is rejected.
  double max_tilt_deg = 10.0;
  // Matches after the projection top-up that a merge needs (the loops need LoopClosingOptions::
  // min_loop_matches, ORB-SLAM2's 40). A merge has no drift gate to catch a look-alike place, and one
  // passes 40: corridor_jump's ring is symmetric and its brick panels and floor tiles repeat, so the
  // far corridor, walked the other way, matches the near one with 42-48 consistent matches (one
  // keyframe after another). 80 is ORB-SLAM3's bar for a place of another map (nProjOptMatches).
  int min_matches = 80;
  // A place the detector found but did not confirm over successive queries (the BoW closer's 3-query
  // consistency: a new map's first keyframes, or an agent's keyframes interleaved with another's, cannot
  // give it in time) is merged when it is confirmed in space instead, as ORB-SLAM3 does: after it passed
  // the verification and min_matches, at least `covisible_confirmations` of the query's best covisible
  // keyframes (5 looked at) must see the matched keyframe's covisible group's points where the verified
  // transform places them, each with >= `confirmation_matches` projection matches.
  int covisible_confirmations = 2;
  int confirmation_matches = 40;
  // A look-alike place passes min_matches on its repeated part alone: corridor_loop's ring is point
  // symmetric in its brick panels, floor tiles and twin checkerboards, and two agents walking it half a
  // ring apart match each other's mirrored corridor with up to 78 matches (80 needed), while the true
  // place gave 81 at its first keyframe. What tells them apart is what is NOT matched: of the points each
  // side's covisible group predicts in the other keyframe's view (the projection test), a true place
  // finds many (measured: 14.1-20.5 % at the merges of corridor_loop's two agents, corridor_jump with
  // both closers and the MH01 halves), a look-alike few (its unique panels do not match: 3.5-9.6 %, the
  // highest at 44 matches). A verified merge needs this share (docs/loop_closing.md, Merging).
  double min_found_share = 0.12;
  bool seam_bundle_adjustment = true;
  LocalBundleAdjustmentOptions seam_ba;
  LoopCorrectionBuilderOptions correction;  // fusion thresholds, essential graph, pose_graph.*
};

// A place of map B recognised from a keyframe of map A, or the other way, verified
// (LoopClosing::verify_place). A is the map that moves: the newer one, whichever keyframe was the query.
struct MapMergeRequest {
  KeyframeId active_kf = kNoId;                // keyframe of A (usually the query)
  KeyframeId matched_kf = kNoId;               // keyframe of B
  Pose3 T_matched_active = Pose3::Identity();  // active_kf's camera in matched_kf's (p_matched = T p_active)
  std::vector<std::pair<PointId, PointId>> matched_points;  // (A-side, B-side) RANSAC inliers
  // The two maps' keyframes, culled ones included (the caller partitions the store by map id).
  std::set<KeyframeId> active_map;
  std::set<KeyframeId> matched_map;
};

struct MapMergeStats {
  int moved_keyframes = 0;  // live keyframes of A
  int moved_points = 0;
  int point_merges = 0;
  int seam_connections = 0;  // keyframe pairs of A and B that share points after the fusion
  LocalBundleAdjustmentResult seam_ba;
  double unobserved_m = -1.0;  // the gate's distance (-1: no temporal bound)
  double allowed_m = -1.0;
  double total_ms = 0.0;
};

struct MapMergeOutput {
  std::string error;  // empty on success: else the input was wrong, or the merge gate rejected it
  bool gate_rejected = false;
  LoopCorrection correction;       // kind kMerge; id 0: the loop closer numbers its corrections
  Pose3 T_BA = Pose3::Identity();  // A's frame into B's frame (the rigid part of the correction)
  MapMergeStats stats;
};

class MapMerge {
 public:
  explicit MapMerge(const MapMergeOptions& options = {}) : options_(options) {}

  // `previous_loop_edges`: keyframe pairs of loops closed before (they stay in the graph).
  MapMergeOutput compute(const Map& map, const PinholeStereo& camera, const MapMergeRequest& request,
                         const std::vector<std::pair<KeyframeId, KeyframeId>>& previous_loop_edges) const;

  // Empty when the merge's implied motion is possible, else why not (the gate above).
  std::string implausible_merge(const Map& map, const MapMergeRequest& request, const Pose3& T_BA,
                                MapMergeStats* stats = nullptr) const;

 private:
  MapMergeOptions options_;
};

}  // namespace heslam

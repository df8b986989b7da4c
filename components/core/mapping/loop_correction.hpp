// A loop correction as the loop closer publishes it (mirrors the LoopCorrection IDL type).
//
// The poses were computed on map version `map_version`; keyframes the mapper created after that
// version are not listed and follow their spanning-tree parent.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"

namespace heslam {

// What produced the correction: a closed loop (essential-graph optimization), the global bundle
// adjustment that follows one (which also sets point positions), or a merge of two maps (the loop
// keyframe's map is welded into the matched keyframe's: poses, seam points and merges).
enum class CorrectionKind { kLoop, kGlobalBundleAdjustment, kMerge };

struct LoopCorrection {
  std::uint64_t id = 0;
  std::uint64_t map_version = 0;                             // map version the correction was computed on
  KeyframeId loop_kf = kNoId;                                // the current keyframe that closed the loop
  KeyframeId matched_kf = kNoId;                             // the old keyframe it matched
  Pose3 T_matched_loop = Pose3::Identity();                  // loop keyframe in the matched keyframe's frame
  std::vector<std::pair<KeyframeId, Pose3>> corrected_T_wc;  // new camera->world poses
  std::vector<std::pair<PointId, PointId>> point_merges;     // (from, into): `from` is replaced
  CorrectionKind kind = CorrectionKind::kLoop;
  // Points that take these positions (after the poses moved); the others move with their reference
  // keyframe.
  std::vector<std::pair<PointId, Eigen::Vector3d>> corrected_points;
};

}  // namespace heslam

// LoopCorrection <-> msg::LoopCorrection (see loop_correction.hpp).
#include "components/messages/loop_correction.hpp"

#include <stdexcept>
#include <string>

#include "components/core/map/ids.hpp"
#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam::messages {

LoopCorrectionMessage::LoopCorrectionMessage(const LoopCorrection& correction) {
  poses_.reserve(correction.corrected_T_wc.size());
  for (const auto& [id, T_wc] : correction.corrected_T_wc) poses_.push_back({id, to_message(T_wc)});
  merges_.reserve(correction.point_merges.size());
  for (const auto& [from, into] : correction.point_merges) merges_.push_back({from, into});
  points_.reserve(correction.corrected_points.size());
  for (const auto& [id, p_w] : correction.corrected_points) points_.push_back({id, {p_w.x(), p_w.y(), p_w.z()}});
  message_.id = correction.id;
  message_.map_version = correction.map_version;
  message_.loop_keyframe_id = correction.loop_kf;
  message_.matched_keyframe_id = correction.matched_kf;
  message_.T_matched_loop = to_message(correction.T_matched_loop);
  runtime::borrow(message_.corrected_poses, poses_);
  runtime::borrow(message_.point_merges, merges_);
  switch (correction.kind) {
    case CorrectionKind::kLoop: message_.kind = heslam_msg_CORRECTION_LOOP; break;
    case CorrectionKind::kGlobalBundleAdjustment: message_.kind = heslam_msg_CORRECTION_GLOBAL_BA; break;
    case CorrectionKind::kMerge: message_.kind = heslam_msg_CORRECTION_MERGE; break;
  }
  runtime::borrow(message_.corrected_points, points_);
}

LoopCorrection to_loop_correction(const msg::LoopCorrection& message) {
  const std::string name = "loop correction " + format_id(message.id);
  LoopCorrection correction;
  correction.id = message.id;
  correction.map_version = message.map_version;
  correction.loop_kf = message.loop_keyframe_id;
  correction.matched_kf = message.matched_keyframe_id;
  correction.T_matched_loop = to_pose(message.T_matched_loop);
  if (!correction.T_matched_loop.matrix().allFinite())
    throw std::runtime_error(name + ": T_matched_loop is not finite");
  for (const msg::CorrectedKeyframePose& entry : runtime::view(message.corrected_poses)) {
    const Pose3 T_wc = to_pose(entry.T_wc);
    if (entry.keyframe_id == kNoId || !T_wc.matrix().allFinite()) {
      throw std::runtime_error(name + ": corrected pose of keyframe " + format_id(entry.keyframe_id) +
                               " has id 0 or is not finite");
    }
    correction.corrected_T_wc.emplace_back(entry.keyframe_id, T_wc);
  }
  for (const msg::PointMerge& merge : runtime::view(message.point_merges)) {
    if (merge.from_id == kNoId || merge.into_id == kNoId || merge.from_id == merge.into_id) {
      throw std::runtime_error(name + ": point merge " + format_id(merge.from_id) + " -> " + format_id(merge.into_id) +
                               " is invalid");
    }
    correction.point_merges.emplace_back(merge.from_id, merge.into_id);
  }
  // Any value may come in an enum field (runtime/wire_enum.hpp): checked as the integer first.
  if (!runtime::wire_value_is_one_of(message.kind, heslam_msg_CORRECTION_LOOP, heslam_msg_CORRECTION_GLOBAL_BA,
                                     heslam_msg_CORRECTION_MERGE)) {
    throw std::runtime_error(name + ": kind " + std::to_string(runtime::wire_value(message.kind)) + " is unknown");
  }
  correction.kind = message.kind == heslam_msg_CORRECTION_GLOBAL_BA ? CorrectionKind::kGlobalBundleAdjustment
                    : message.kind == heslam_msg_CORRECTION_MERGE   ? CorrectionKind::kMerge
                                                                    : CorrectionKind::kLoop;
  for (const msg::CorrectedPointPosition& entry : runtime::view(message.corrected_points)) {
    const Eigen::Vector3d p_w(entry.position_w_m[0], entry.position_w_m[1], entry.position_w_m[2]);
    if (entry.point_id == kNoId || !p_w.allFinite()) {
      throw std::runtime_error(name + ": corrected position of point " + format_id(entry.point_id) +
                               " has id 0 or is not finite");
    }
    correction.corrected_points.emplace_back(entry.point_id, p_w);
  }
  return correction;
}

}  // namespace heslam::messages

// IDL <-> core conversions of heslam-local-mapper (see message_adapter.hpp).
#include "components/local_mapper/message_adapter.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

#include "components/frontend/message_adapter.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam::local_mapper {

msg::KeyframeState to_state_message(const Keyframe& keyframe, std::uint64_t map_version,
                                    std::vector<msg::CovisibleKeyframe>& covisible_buffer) {
  msg::KeyframeState message{};
  message.id = keyframe.id;
  message.map_version = map_version;
  message.T_wc = frontend::to_message(keyframe.T_wc);
  message.parent_id = keyframe.parent;
  message.culled = keyframe.culled;
  covisible_buffer.clear();
  for (const auto& [neighbour, weight] : keyframe.covisible) {
    covisible_buffer.push_back({neighbour, static_cast<std::uint32_t>(std::max(weight, 0))});
  }
  runtime::borrow(message.covisible, covisible_buffer);
  return message;
}

msg::MapPointState to_state_message(const MapPoint& point, std::uint64_t map_version,
                                    std::vector<msg::PointObservation>& observation_buffer) {
  msg::MapPointState message{};
  message.id = point.id;
  message.map_version = map_version;
  for (int k = 0; k < 3; ++k) {
    message.position_w_m[k] = point.p_w[k];
    message.normal_w[k] = static_cast<float>(point.normal[k]);
  }
  static_assert(sizeof(message.descriptor) == sizeof(Descriptor), "IDL descriptor size must match the core's");
  std::memcpy(message.descriptor, point.descriptor.data(), sizeof(message.descriptor));
  message.min_distance_m = point.min_distance_m;
  message.max_distance_m = point.max_distance_m;
  message.reference_keyframe_id = point.reference_kf;
  message.culled = point.culled;
  message.merged_into = point.merged_into;
  observation_buffer.clear();
  for (const auto& [keyframe, index] : point.observations) {
    observation_buffer.push_back({keyframe, static_cast<std::uint32_t>(index)});
  }
  runtime::borrow(message.observations, observation_buffer);
  return message;
}

msg::MapPointState merged_state_message(PointId id, PointId into, std::uint64_t map_version) {
  msg::MapPointState message{};
  message.id = id;
  message.map_version = map_version;
  message.culled = true;
  message.merged_into = into;
  return message;
}

msg::KeyframeState keyframe_version_marker(std::uint64_t map_version, std::uint64_t correction_id) {
  msg::KeyframeState message{};
  message.id = frontend::kVersionMarkerId;
  message.map_version = map_version;
  message.correction_id = correction_id;
  message.T_wc.orientation_xyzw[3] = 1.0;  // a valid identity, for tools that print it
  return message;
}

msg::MapPointState point_version_marker(std::uint64_t map_version) {
  msg::MapPointState message{};
  message.id = frontend::kVersionMarkerId;
  message.map_version = map_version;
  return message;
}

LoopCorrection to_loop_correction(const msg::LoopCorrection& message) {
  const std::string name = "loop correction " + std::to_string(message.id);
  LoopCorrection correction;
  correction.id = message.id;
  correction.map_version = message.map_version;
  correction.loop_kf = message.loop_keyframe_id;
  correction.matched_kf = message.matched_keyframe_id;
  correction.T_matched_loop = frontend::to_pose(message.T_matched_loop);
  if (!correction.T_matched_loop.matrix().allFinite()) throw std::runtime_error(name + ": T_matched_loop is not finite");
  for (const msg::CorrectedKeyframePose& entry : runtime::view(message.corrected_poses)) {
    const Pose3 T_wc = frontend::to_pose(entry.T_wc);
    if (entry.keyframe_id == kNoId || !T_wc.matrix().allFinite()) {
      throw std::runtime_error(name + ": corrected pose of keyframe " + std::to_string(entry.keyframe_id) +
                               " has id 0 or is not finite");
    }
    correction.corrected_T_wc.emplace_back(entry.keyframe_id, T_wc);
  }
  for (const msg::PointMerge& merge : runtime::view(message.point_merges)) {
    if (merge.from_id == kNoId || merge.into_id == kNoId || merge.from_id == merge.into_id) {
      throw std::runtime_error(name + ": point merge " + std::to_string(merge.from_id) + " -> " +
                               std::to_string(merge.into_id) + " is invalid");
    }
    correction.point_merges.emplace_back(merge.from_id, merge.into_id);
  }
  // Any value may come in an enum field (runtime/wire_enum.hpp): checked as the integer first.
  if (!runtime::wire_value_is_one_of(message.kind, heslam_msg_CORRECTION_LOOP, heslam_msg_CORRECTION_GLOBAL_BA)) {
    throw std::runtime_error(name + ": kind " + std::to_string(runtime::wire_value(message.kind)) + " is unknown");
  }
  correction.kind = message.kind == heslam_msg_CORRECTION_GLOBAL_BA ? CorrectionKind::kGlobalBundleAdjustment
                                                             : CorrectionKind::kLoop;
  for (const msg::CorrectedPointPosition& entry : runtime::view(message.corrected_points)) {
    const Eigen::Vector3d p_w(entry.position_w_m[0], entry.position_w_m[1], entry.position_w_m[2]);
    if (entry.point_id == kNoId || !p_w.allFinite()) {
      throw std::runtime_error(name + ": corrected position of point " + std::to_string(entry.point_id) +
                               " has id 0 or is not finite");
    }
    correction.corrected_points.emplace_back(entry.point_id, p_w);
  }
  return correction;
}

}  // namespace heslam::local_mapper

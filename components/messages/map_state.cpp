// Keyframe and map point state <-> core Map (see map_state.hpp).
#include "components/messages/map_state.hpp"

#include <algorithm>
#include <cstring>

#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::messages {
namespace {

constexpr std::size_t kDescriptorBytes = sizeof(Descriptor);

bool observes_keyframe(const MapPoint& point, KeyframeId keyframe_id) {
  return std::any_of(point.observations.begin(), point.observations.end(),
                     [&](const auto& observation) { return observation.first == keyframe_id; });
}

// The keyframe slot an observation names, or null when the keyframe is unknown here or the index is
// out of its range.
PointId* slot_of(Map& map, KeyframeId keyframe_id, int keypoint_index) {
  Keyframe* keyframe = map.keyframe(keyframe_id);
  if (keyframe == nullptr || keypoint_index < 0 ||
      static_cast<std::size_t>(keypoint_index) >= keyframe->point_ids.size()) {
    return nullptr;
  }
  return &keyframe->point_ids[static_cast<std::size_t>(keypoint_index)];
}

// Removes the point from every keyframe that observes it. With a replacement (a merge) a keyframe
// sees the replacement instead, unless the replacement already observes that keyframe: then the
// slot is emptied, as the mapper's replace_point does, so a keyframe never sees one point twice.
void replace_in_keyframes(Map& map, const MapPoint& point, MapPoint* replacement) {
  for (const auto& [keyframe_id, keypoint_index] : point.observations) {
    PointId* slot = slot_of(map, keyframe_id, keypoint_index);
    if (slot == nullptr || *slot != point.id) continue;
    if (replacement == nullptr || observes_keyframe(*replacement, keyframe_id)) {
      *slot = kNoId;
      continue;
    }
    *slot = replacement->id;
    replacement->observations.emplace_back(keyframe_id, keypoint_index);
  }
}

}  // namespace

msg::KeyframeState to_state_message(const Keyframe& keyframe, std::uint64_t map_version,
                                    std::vector<msg::CovisibleKeyframe>& covisible_buffer) {
  msg::KeyframeState message{};
  message.id = keyframe.id;
  message.map_version = map_version;
  message.map_id = keyframe.map_id;
  message.T_wc = to_message(keyframe.T_wc);
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
  message.map_id = point.map_id;
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
  message.id = kVersionMarkerId;
  message.map_version = map_version;
  message.correction_id = correction_id;
  message.T_wc.orientation_xyzw[3] = 1.0;  // a valid identity, for tools that print it
  return message;
}

msg::MapPointState point_version_marker(std::uint64_t map_version) {
  msg::MapPointState message{};
  message.id = kVersionMarkerId;
  message.map_version = map_version;
  return message;
}

bool is_version_marker(const msg::KeyframeState& state) { return state.id == kVersionMarkerId; }
bool is_version_marker(const msg::MapPointState& state) { return state.id == kVersionMarkerId; }

bool apply_keyframe_state(Map& map, const msg::KeyframeState& state) {
  Keyframe* keyframe = map.keyframe(state.id);
  if (keyframe == nullptr) return false;
  keyframe->map_id = state.map_id;
  keyframe->T_wc = to_pose(state.T_wc);
  keyframe->parent = state.parent_id;
  keyframe->covisible.clear();
  for (const msg::CovisibleKeyframe& neighbour : runtime::view(state.covisible)) {
    keyframe->covisible.emplace_back(neighbour.id, static_cast<int>(neighbour.weight));
  }
  keyframe->culled = state.culled;
  // A culled keyframe stays (flagged) so frames referencing it keep their anchor; its data goes, as in
  // the mapper (a culled keyframe is never revived: the mapper sends no features again).
  if (keyframe->culled) release_culled_keyframe(*keyframe);
  return true;
}

void apply_point_state(Map& map, const msg::MapPointState& state) {
  if (state.merged_into != kNoId) {
    erase_point(map, state.id, state.merged_into);
    return;
  }
  MapPoint& point = map.points[state.id];  // creates it when the mapper made it (triangulation)
  point.id = state.id;
  point.map_id = state.map_id;
  point.p_w = Eigen::Vector3d(state.position_w_m[0], state.position_w_m[1], state.position_w_m[2]);
  std::memcpy(point.descriptor.data(), state.descriptor, kDescriptorBytes);
  point.normal = Eigen::Vector3d(state.normal_w[0], state.normal_w[1], state.normal_w[2]);
  point.min_distance_m = state.min_distance_m;
  point.max_distance_m = state.max_distance_m;
  point.reference_kf = state.reference_keyframe_id;
  point.culled = state.culled;  // the tracker's searches skip culled points
  point.merged_into = kNoId;
  // The state's observations are the whole truth: a keyframe slot the mapper took from this point
  // (a BA outlier, a fusion) is emptied here too, unless another point's state claimed it already.
  // Without this, the mirror's keyframes kept stale associations, and which ones depended on the
  // order the states were applied in.
  const auto observations = runtime::view(state.observations);
  for (const auto& [keyframe_id, keypoint_index] : point.observations) {
    const bool kept = std::any_of(observations.begin(), observations.end(), [&](const msg::PointObservation& o) {
      return o.keyframe_id == keyframe_id && static_cast<int>(o.keypoint_index) == keypoint_index;
    });
    PointId* slot = slot_of(map, keyframe_id, keypoint_index);
    if (!kept && slot != nullptr && *slot == state.id) *slot = kNoId;
  }
  point.observations.clear();
  for (const msg::PointObservation& observation : observations) {
    point.observations.emplace_back(observation.keyframe_id, static_cast<int>(observation.keypoint_index));
    // The mapper may add observations (fusion, triangulation matches): the keyframe sees the point.
    Keyframe* keyframe = map.keyframe(observation.keyframe_id);
    if (keyframe != nullptr && observation.keypoint_index < keyframe->point_ids.size()) {
      keyframe->point_ids[observation.keypoint_index] = state.id;
    }
  }
}

void erase_point(Map& map, PointId id, PointId replacement) {
  auto it = map.points.find(id);
  if (it == map.points.end()) return;
  MapPoint* into = replacement != id ? map.point(replacement) : nullptr;
  replace_in_keyframes(map, it->second, into);
  map.points.erase(it);
}

void cull_point(Map& map, PointId id) {
  MapPoint* point = map.point(id);
  if (point == nullptr) return;
  replace_in_keyframes(map, *point, nullptr);
  point->culled = true;
}

}  // namespace heslam::messages

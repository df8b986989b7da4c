// The loop closer's mirror of the map (see map_mirror.hpp).
#include "components/loop_closer/map_mirror.hpp"

#include <stdexcept>
#include <string>

#include "components/core/map/ids.hpp"
#include "components/messages/camera.hpp"
#include "components/messages/checks.hpp"
#include "components/messages/keyframe.hpp"
#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::loop_closer {

void MapMirror::add_keyframe(const msg::Keyframe& message) {
  if (auto problem = messages::check(message)) throw std::runtime_error(*problem);
  messages::DecodedKeyframe decoded = messages::to_keyframe(message);
  Keyframe& incoming = decoded.keyframe;
  const std::string name = "keyframe " + format_id(message.id);
  const PinholeStereo camera = messages::to_camera(message.camera);
  if (!(camera.fx_px > 0.0) || !(camera.baseline_m > 0.0)) {
    throw std::runtime_error(name + ": camera fx " + std::to_string(camera.fx_px) + " px, baseline " +
                             std::to_string(camera.baseline_m) + " m (expected both > 0)");
  }
  if (!camera_) camera_ = camera;
  // The frontend's point ids at creation: the mapper's point states (observations) are authoritative,
  // so only ids of points this mirror already holds with that observation survive (insert()).
  const KeyframeId id = message.id;
  if (map_.keyframe(id) != nullptr) return;  // sent again (a restarted frontend): the copy has it
  for (std::size_t i = 0; i < incoming.point_ids.size(); ++i) incoming.point_ids[i] = kNoId;
  auto pending = pending_states_.find(id);
  if (pending == pending_states_.end()) {
    if (admission_ == KeyframeAdmission::kWithSample) {
      insert(std::move(incoming));
    } else {
      awaiting_state_[id] = std::move(incoming);  // the frontend's pose: not the map's yet
    }
    return;
  }
  Keyframe& keyframe = insert(std::move(incoming));
  keyframe.map_id = pending->second.map_id;
  keyframe.T_wc = pending->second.T_wc;
  keyframe.parent = pending->second.parent;
  keyframe.covisible = std::move(pending->second.covisible);
  keyframe.culled = pending->second.culled;
  if (keyframe.culled) release_culled_keyframe(keyframe);
  pending_states_.erase(pending);
}

void MapMirror::load(Map map) {
  // The map's own version: the mapper's versions go on from it, so its markers still count.
  map_ = std::move(map);
}

Keyframe& MapMirror::insert(Keyframe incoming) {
  const KeyframeId id = incoming.id;
  Keyframe& keyframe = map_.keyframes[id] = std::move(incoming);
  for (const auto& [point_id, point] : map_.points) {
    for (const auto& [kf_id, index] : point.observations) {
      if (kf_id == id && index >= 0 && static_cast<std::size_t>(index) < keyframe.point_ids.size()) {
        keyframe.point_ids[static_cast<std::size_t>(index)] = point_id;
      }
    }
  }
  return keyframe;
}

bool MapMirror::knows_map(MapId map_id) const {
  if (mapped_maps_.count(map_id) != 0) return true;
  for (const auto& [id, keyframe] : map_.keyframes) {
    if (keyframe.map_id == map_id) return true;  // a loaded map's (load()), before its states come
  }
  return false;
}

void MapMirror::apply_keyframe_state(const msg::KeyframeState& message) {
  if (messages::is_version_marker(message)) return;  // count_markers() takes those
  if (auto problem = messages::check(message)) throw std::runtime_error(*problem);
  mapped_maps_.insert(message.map_id);
  if (auto awaiting = awaiting_state_.find(message.id); awaiting != awaiting_state_.end()) {
    insert(std::move(awaiting->second));
    awaiting_state_.erase(awaiting);
  }
  if (messages::apply_keyframe_state(map_, message)) return;
  PendingState& pending = pending_states_[message.id];
  pending.map_id = message.map_id;
  pending.T_wc = messages::to_pose(message.T_wc);
  pending.parent = message.parent_id;
  pending.covisible.clear();
  for (const msg::CovisibleKeyframe& neighbour : runtime::view(message.covisible)) {
    pending.covisible.emplace_back(neighbour.id, static_cast<int>(neighbour.weight));
  }
  pending.culled = message.culled;
}

void MapMirror::apply_point_state(const msg::MapPointState& message) {
  if (messages::is_version_marker(message)) return;
  if (auto problem = messages::check(message)) throw std::runtime_error(*problem);
  messages::apply_point_state(map_, message);
}

void MapMirror::point_disposed(PointId id) {
  if (id != messages::kVersionMarkerId) messages::erase_point(map_, id);
}

void MapMirror::count_markers(const messages::MirrorVersion& markers) {
  version_.keyframe_states = std::max(version_.keyframe_states, markers.keyframe_states);
  version_.point_states = std::max(version_.point_states, markers.point_states);
  map_.version = std::max(map_.version, version_.complete());
}

}  // namespace heslam::loop_closer

// The loop closer's read-only copy of the map: keyframes from the frontend's Keyframe samples, their
// refined state and the map points from the local mapper's state topics (all transient-local, so a
// late or restarted loop closer rebuilds the whole map from DDS).
//
// Samples of different topics arrive in any order: a keyframe state or a point observation that
// refers to a keyframe not yet received is kept and applied when the keyframe arrives.
//
// The loop closer's copy (KeyframeAdmission::kWithMapperState) takes a keyframe only with its first
// state from the mapper. The Keyframe sample alone holds the frontend's pose at creation, which in
// real time may predate a loop correction the mapper applied since (the mapper moves such a keyframe
// with its reference keyframe when it inserts it): a global BA computed on a copy holding that pose
// listed it as the keyframe's new pose, and the mapper moved the keyframe back into the uncorrected
// frame with every keyframe created on it since (the 1 m seam of the real-time street,
// docs/loop_closer.md). A keyframe sent again once in the copy (a restarted frontend) is ignored.
#pragma once

#include <map>
#include <optional>
#include <set>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/messages/map_state.hpp"
#include "runtime/messages.hpp"

namespace heslam::loop_closer {

// When a keyframe enters map().
enum class KeyframeAdmission {
  kWithSample,       // at once, at the frontend's pose until the mapper's state comes (the viewer)
  kWithMapperState,  // once mapped: every keyframe of the copy is in the mapper's frame (loop closing)
};

class MapMirror {
 public:
  explicit MapMirror(KeyframeAdmission admission = KeyframeAdmission::kWithSample) : admission_(admission) {}

  // Throws std::runtime_error naming the keyframe when the sample is malformed (messages::check:
  // lengths, non-finite numbers, bad camera); the mirror is unchanged then.
  void add_keyframe(const msg::Keyframe& message);
  // Before any sample: the keyframes (with features) and points of a map the local mapper loaded
  // (multi-session mapping), which no Keyframe sample of this run carries. The mapper's states of
  // them replace these values as they arrive.
  void load(Map map);
  // Throws std::runtime_error naming the keyframe / point when messages::check refuses the sample
  // (non-finite pose or position, zero ids, ...).
  void apply_keyframe_state(const msg::KeyframeState& message);
  void apply_point_state(const msg::MapPointState& message);
  // A disposed point instance: removed by the mapper (a culled or merged point).
  void point_disposed(PointId id);
  // The version markers taken since the readers were last drained (messages::MirrorVersion): map().version
  // becomes the mapper's map version this copy holds completely.
  void count_markers(const messages::MirrorVersion& markers);

  const Map& map() const { return map_; }
  // Whether the mapper holds keyframes of `map_id`: a state of one came (before its keyframe sample,
  // too), or the map holds one (a loaded map's).
  bool knows_map(MapId map_id) const;
  // kWithMapperState: keyframes received from the frontend without a mapper state yet (not in map()).
  std::size_t keyframes_awaiting_state() const { return awaiting_state_.size(); }
  // The rectified camera of the first keyframe (every keyframe of a run shares it).
  const std::optional<PinholeStereo>& camera() const { return camera_; }

 private:
  struct PendingState {
    MapId map_id = kFirstMapId;  // the mapper's (a merge moves a keyframe into another map)
    Pose3 T_wc;
    KeyframeId parent = kNoId;
    std::vector<std::pair<KeyframeId, int>> covisible;
    bool culled = false;
  };

  // Puts a keyframe into map_ with the point ids of the observations already received.
  Keyframe& insert(Keyframe keyframe);

  KeyframeAdmission admission_;
  Map map_;
  messages::MirrorVersion version_;
  std::optional<PinholeStereo> camera_;
  std::map<KeyframeId, PendingState> pending_states_;  // states of keyframes not received yet
  std::set<MapId> mapped_maps_;                        // the maps of every keyframe state received
  // Keyframe samples without a mapper state yet: kept out of map_ until their first state.
  std::map<KeyframeId, Keyframe> awaiting_state_;
};

}  // namespace heslam::loop_closer

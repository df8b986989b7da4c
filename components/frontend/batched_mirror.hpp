// The local mapper's state applied to the frontend's map one complete map version at a time.
//
// The mapper writes a batch of states (a keyframe's, a correction's) and ends it with version
// markers (MirrorVersion). Applied sample by sample, a mirror would hold half a batch for as long as
// the batch takes to arrive — a loop correction republishes every point, about a second — and the
// tracker would track frames against corrected keyframes and uncorrected points at once: their
// poses relative to their reference keyframe, which the recorder writes, were then wrong. Here the
// states wait until their batch is complete and are applied together, so the map the tracker sees
// is always one of the mapper's versions.
//
// A correction's batch (its keyframe marker names the correction) also moves the keyframes this
// frontend made that the mapper had not yet inserted when it applied the correction: they were
// tracked in the old frame, and the mapper moves them with their reference keyframe when they reach
// it (components/core/mapping/correction_history.hpp); the mirror does the same at once, with the
// points they created, so the tracker does not wait for the mapper's states of them.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <vector>

#include "components/core/map/map.hpp"
#include "components/messages/map_state.hpp"
#include "runtime/messages.hpp"

namespace heslam::frontend {

class BatchedMirror {
 public:
  struct Applied {
    int keyframe_states = 0;
    int unknown_keyframe_states = 0;  // for keyframes this map does not hold (ignored)
    int point_states = 0;
    bool correction = false;  // a loop correction's batch was among them
    int keyframes_moved = 0;  // own keyframes in flight moved with their reference
  };

  // Samples as taken from the readers (markers included); copied.
  void add(const msg::KeyframeState& state);
  void add(const msg::MapPointState& state);
  // A point the mapper removed (dispose): culled after any state of it still waiting.
  void dispose_point(PointId id);
  // The mapper's acknowledgement of a correction it applied, producing `map_version`: the same news
  // as the batch's marker, over another topic. A marker may be replaced by the next batch's before a
  // busy reader takes it (keep-last), the acknowledgement cannot (lockstep QoS keeps 64). False when
  // that version was applied already without being known as a correction (then only the last frame
  // can still follow its reference keyframe).
  bool correction_acknowledged(std::uint64_t map_version);
  // A keyframe this frontend made and published (the mapper moves it, too, should it predate a
  // correction): what it was tracked against.
  void own_keyframe(KeyframeId id, KeyframeId reference, std::uint64_t tracked_map_version);

  // After the readers were drained: the markers taken count, and every waiting state of a complete
  // version is applied to `map`.
  Applied apply(Map& map);

  // The mapper's map version this mirror holds completely (all of it applied).
  const messages::MirrorVersion& version() const { return version_; }
  std::size_t waiting() const { return keyframe_states_.size() + point_states_.size(); }
  // The largest counter of a keyframe / point id with creator `tag` the states named (ids.hpp), 0
  // if none: a restarted frontend's ids continue above its predecessor's.
  std::uint64_t largest_keyframe_counter(std::uint8_t tag) const;
  std::uint64_t largest_point_counter(std::uint8_t tag) const;

 private:
  struct KeyframeStateCopy {
    msg::KeyframeState sample{};
    std::vector<msg::CovisibleKeyframe> covisible;
  };
  struct PointStateCopy {
    msg::MapPointState sample{};
    std::vector<msg::PointObservation> observations;
    bool disposed_after = false;
  };
  struct InFlight {
    KeyframeId reference = kNoId;
    std::uint64_t tracked_map_version = 0;
  };

  void move_keyframes_in_flight(Map& map, const std::map<KeyframeId, Pose3>& old_T_wc, std::uint64_t correction_version,
                                Applied& applied);

  messages::MirrorVersion version_;
  messages::MirrorVersion markers_;              // taken since the last apply
  std::set<std::uint64_t> correction_versions_;  // marked, not yet applied
  std::set<std::uint64_t> applied_corrections_;  // versions applied as corrections
  std::map<KeyframeId, KeyframeStateCopy> keyframe_states_;
  std::map<PointId, PointStateCopy> point_states_;
  std::set<PointId> pending_disposes_;                              // disposes of points with no state waiting
  std::map<KeyframeId, InFlight> in_flight_;                        // own keyframes without a mapper state yet
  std::map<std::uint8_t, std::uint64_t> largest_keyframe_counter_;  // by creator tag, over every id seen
  std::map<std::uint8_t, std::uint64_t> largest_point_counter_;
};

}  // namespace heslam::frontend

// The local mapper's keyframe and map point state on the wire: written by the mapper after every
// batch (a keyframe's, a correction's, the whole map after a restart) and applied to a core Map by
// every reader that mirrors the map (the frontend, the loop closer, the viewer). Both directions
// live here so the version-marker protocol is defined once.
//
// Outgoing samples borrow their sequences from a buffer the caller owns; the buffer must outlive the
// write() that sends the sample (writes serialize synchronously, so one buffer is reused per write).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "components/core/map/map.hpp"
#include "runtime/messages.hpp"

namespace heslam::messages {

// --- reading: the mapper's state mirrored into a core Map ---
// Which map version a mirror holds completely. The local mapper ends every batch of state samples
// (per keyframe, per correction, the whole map after a restart) with a version marker on both state
// topics: a sample of id kVersionMarkerId carrying the batch's map version, written by the same
// writer after the batch. One writer's samples arrive in order, so once both markers of version v
// arrived, every state of v arrived too (or was superseded by a newer one). A map version read off
// ordinary samples would only say that *some* state of it arrived (docs/topics.md).
inline constexpr std::uint64_t kVersionMarkerId = 0;
// A reader's take returns instances in key order, not in arrival order, so a marker may come out
// before states that arrived ahead of it: drain both readers until empty, then count the markers
// taken meanwhile.
struct MirrorVersion {
  std::uint64_t keyframe_states = 0;  // the newest marker of each topic
  std::uint64_t point_states = 0;
  std::uint64_t complete() const { return std::min(keyframe_states, point_states); }
};
bool is_version_marker(const msg::KeyframeState& state);
bool is_version_marker(const msg::MapPointState& state);

// Refined pose, spanning-tree parent, covisibility and culled flag of a keyframe the map holds (a
// culled keyframe stays, flagged). Returns false when the keyframe is unknown here (state ignored).
// map.version is left alone: only the markers advance it.
bool apply_keyframe_state(Map& map, const msg::KeyframeState& state);
// Creates or updates the point (a culled one stays, flagged); a merged point is removed and the
// observing keyframes' point ids are pointed at the point it merged into. The keyframes' point ids
// follow the state's observations exactly (slots it no longer names are emptied), so a batch of
// states leaves the same map whatever order it is applied in.
void apply_point_state(Map& map, const msg::MapPointState& state);
// Removes a point; the keyframes observing it see `replacement` instead (kNoId: nothing).
void erase_point(Map& map, PointId id, PointId replacement = kNoId);
// A point the mapper removed (its dispose), kept flagged culled for frames that still name it: the
// keyframes no longer see it, as in the mapper's map. A later state of it revives it.
void cull_point(Map& map, PointId id);

// --- writing (the local mapper) ---
// State of a keyframe the map holds (a culled keyframe is published with culled = true, not
// disposed: frames anchored to it still need its pose).
msg::KeyframeState to_state_message(const Keyframe& keyframe, std::uint64_t map_version,
                                    std::vector<msg::CovisibleKeyframe>& covisible_buffer);

// State of a live map point.
msg::MapPointState to_state_message(const MapPoint& point, std::uint64_t map_version,
                                    std::vector<msg::PointObservation>& observation_buffer);

// The last sample of a point that merged into another one (readers redirect observations), written
// just before the instance is disposed.
msg::MapPointState merged_state_message(PointId id, PointId into, std::uint64_t map_version);

// The end-of-batch markers written after every batch of states (MirrorVersion says why).
// `correction_id`: the batch applied that loop correction (0: a keyframe's batch, or a republish).
msg::KeyframeState keyframe_version_marker(std::uint64_t map_version, std::uint64_t correction_id = 0);
msg::MapPointState point_version_marker(std::uint64_t map_version);

}  // namespace heslam::messages

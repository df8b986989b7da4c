// The ONE place where heslam-local-mapper converts between IDL samples and core types: keyframe
// state and map point state out, loop corrections in. Keyframe samples and poses are decoded with the
// frontend's adapter (components/frontend/message_adapter.hpp), so both ends share one definition.
//
// Outgoing samples borrow their sequences from a buffer the caller owns; the buffer must outlive the
// write() that sends the sample (writes serialize synchronously, so one buffer is reused per write).
#pragma once

#include <cstdint>
#include <vector>

#include "components/core/map/map.hpp"
#include "components/core/mapping/loop_correction.hpp"
#include "runtime/messages.hpp"

namespace heslam::local_mapper {

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

// The end-of-batch markers written after every batch of states (frontend::MirrorVersion says why).
// `correction_id`: the batch applied that loop correction (0: a keyframe's batch, or a republish).
msg::KeyframeState keyframe_version_marker(std::uint64_t map_version, std::uint64_t correction_id = 0);
msg::MapPointState point_version_marker(std::uint64_t map_version);

// Throws std::runtime_error naming the correction when a pose is not finite or an id is 0.
LoopCorrection to_loop_correction(const msg::LoopCorrection& message);

}  // namespace heslam::local_mapper

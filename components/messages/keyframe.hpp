// Keyframes on the wire (frontend -> local mapper, loop closer, recorder, viewer): a core Keyframe
// with its features, point ids and the points it created, and back.
// KeyframeMessage borrows its sequences from buffers it owns, so it must outlive the write() that
// sends it; to_keyframe copies what it keeps.
#pragma once

#include <cstdint>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "runtime/messages.hpp"

namespace heslam::messages {

class KeyframeMessage {
 public:
  // `reference_kf` and `tracked_map_version`: what the keyframe was tracked against
  // (TrackResult::new_keyframe_reference, the mapper's map version the mirror held completely).
  KeyframeMessage(const Keyframe& keyframe, std::uint64_t frame_seq, const std::vector<MapPoint>& new_points,
                  const PinholeStereo& camera, KeyframeId reference_kf, std::uint64_t tracked_map_version);
  KeyframeMessage(const KeyframeMessage&) = delete;
  KeyframeMessage& operator=(const KeyframeMessage&) = delete;
  const msg::Keyframe& get() const { return message_; }

 private:
  std::vector<msg::KeyframeKeypoint> keypoints_;
  std::vector<std::uint8_t> descriptors_;
  std::vector<std::uint64_t> point_ids_;
  std::vector<msg::NewStereoPoint> new_points_;
  msg::Keyframe message_{};
};

// A keyframe sample back into core types (the features, point ids and new points), for readers that
// rebuild a map from the keyframes topic. Throws std::runtime_error when sequence lengths disagree.
struct DecodedKeyframe {
  Keyframe keyframe;
  std::vector<MapPoint> new_points;       // position and creating observation only
  KeyframeId reference_kf = kNoId;        // the keyframe it was tracked against (kNoId: none)
  std::uint64_t tracked_map_version = 0;  // the mapper's map version the frontend tracked it in
};
DecodedKeyframe to_keyframe(const msg::Keyframe& message);

}  // namespace heslam::messages

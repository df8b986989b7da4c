// The ONE place where the frontend (and the recorder) convert between IDL samples and core types:
// poses, calibration, stereo images, odometry, keyframes, and the mapper's keyframe / point state
// mirrored into the tracker's local map.
//
// Outgoing messages borrow their sequences from buffers owned by the *Message classes below, so a
// message object must outlive the write() that sends it. Incoming conversions copy what they keep.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/tracker.hpp"
#include "runtime/messages.hpp"

namespace heslam::frontend {

// --- poses ---
msg::Pose to_message(const Pose3& T_ab);
Pose3 to_pose(const msg::Pose& pose);  // the quaternion is normalised (it crossed a wire)

// --- camera input ---
// Throws std::runtime_error naming the calibration source and field when the message is unusable.
StereoCalibration to_calibration(const msg::StereoCalibration& message);
PinholeStereo to_camera(const msg::RectifiedStereoCamera& message);
msg::RectifiedStereoCamera to_message(const PinholeStereo& camera);

// The raw images of a frame as 8-bit grey. MONO8 pixels are wrapped without a copy (valid while the
// message lives); BGR8 is converted. Throws std::runtime_error naming the frame when the byte counts
// do not match width x height x channels.
struct GreyPair {
  cv::Mat left;
  cv::Mat right;
};
GreyPair to_grey_images(const msg::StereoFrame& frame);

// --- odometry ---
struct StageTiming {
  std::string stage;  // at most 31 characters (IDL string<31>); longer names are cut
  double ms = 0.0;
};

class OdometryMessage {
 public:
  OdometryMessage(std::int64_t stamp_ns, std::uint64_t seq, const TrackResult& result, std::uint32_t keypoints,
                  const std::vector<StageTiming>& timings);
  OdometryMessage(const OdometryMessage&) = delete;
  OdometryMessage& operator=(const OdometryMessage&) = delete;
  const msg::Odometry& get() const { return message_; }

 private:
  std::vector<msg::StageTime> stage_times_;
  msg::Odometry message_{};
};

heslam_msg_TrackingState to_message(TrackingState state);

// --- keyframes (frontend -> mapper, recorder) ---
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
  std::vector<MapPoint> new_points;  // position and creating observation only
  KeyframeId reference_kf = kNoId;   // the keyframe it was tracked against (kNoId: none)
  std::uint64_t tracked_map_version = 0;  // the mapper's map version the frontend tracked it in
};
DecodedKeyframe to_keyframe(const msg::Keyframe& message);

// --- the mapper's state mirrored into the tracker's map ---
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
// observing keyframes' point ids are pointed at the point it merged into.
void apply_point_state(Map& map, const msg::MapPointState& state);
// Removes a point; the keyframes observing it see `replacement` instead (kNoId: nothing).
void erase_point(Map& map, PointId id, PointId replacement = kNoId);

}  // namespace heslam::frontend

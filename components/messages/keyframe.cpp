// Keyframe <-> msg::Keyframe (see keyframe.hpp).
#include "components/messages/keyframe.hpp"

#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "components/messages/camera.hpp"
#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::messages {
namespace {

constexpr std::size_t kDescriptorBytes = sizeof(Descriptor);

}  // namespace

KeyframeMessage::KeyframeMessage(const Keyframe& keyframe, std::uint64_t frame_seq,
                                 const std::vector<MapPoint>& new_points, const PinholeStereo& camera,
                                 KeyframeId reference_kf, std::uint64_t tracked_map_version) {
  const StereoFeatures& features = keyframe.features;
  message_.id = keyframe.id;
  message_.stamp_ns = keyframe.stamp_ns;
  message_.frame_seq = frame_seq;
  message_.map_id = keyframe.map_id;
  message_.T_wc = to_message(keyframe.T_wc);
  message_.reference_keyframe_id = reference_kf;
  message_.tracked_map_version = tracked_map_version;
  message_.camera = to_message(camera);
  message_.pyramid_levels = static_cast<std::uint32_t>(features.pyramid.levels);
  message_.scale_factor = features.pyramid.scale_factor;

  keypoints_.resize(features.size());
  descriptors_.resize(features.size() * kDescriptorBytes);
  for (std::size_t i = 0; i < features.size(); ++i) {
    const Keypoint& kp = features.keypoints[i];
    keypoints_[i] = {kp.u_px, kp.v_px, features.u_right_px[i], features.depth_m[i], kp.angle_deg, kp.octave};
    std::memcpy(descriptors_.data() + i * kDescriptorBytes, features.descriptors[i].data(), kDescriptorBytes);
  }
  point_ids_.assign(keyframe.point_ids.begin(), keyframe.point_ids.end());
  new_points_.reserve(new_points.size());
  for (const MapPoint& point : new_points) {
    msg::NewStereoPoint entry{};
    entry.id = point.id;
    // The creating observation is the new keyframe's own keypoint.
    for (const auto& [observer, index] : point.observations) {
      if (observer == keyframe.id) entry.keypoint_index = static_cast<std::uint32_t>(index);
    }
    for (int k = 0; k < 3; ++k) entry.position_w_m[k] = point.p_w[k];
    new_points_.push_back(entry);
  }
  runtime::borrow(message_.keypoints, keypoints_);
  runtime::borrow(message_.descriptors, descriptors_);
  runtime::borrow(message_.point_ids, point_ids_);
  runtime::borrow(message_.new_points, new_points_);
}

DecodedKeyframe to_keyframe(const msg::Keyframe& message) {
  const auto keypoints = runtime::view(message.keypoints);
  const auto descriptors = runtime::view(message.descriptors);
  const auto point_ids = runtime::view(message.point_ids);
  if (descriptors.size() != keypoints.size() * kDescriptorBytes || point_ids.size() != keypoints.size()) {
    throw std::runtime_error("keyframe " + std::to_string(message.id) + ": " + std::to_string(keypoints.size()) +
                             " keypoints but " + std::to_string(descriptors.size()) + " descriptor bytes and " +
                             std::to_string(point_ids.size()) + " point ids");
  }
  DecodedKeyframe decoded;
  decoded.reference_kf = message.reference_keyframe_id;
  decoded.tracked_map_version = message.tracked_map_version;
  Keyframe& keyframe = decoded.keyframe;
  keyframe.id = message.id;
  keyframe.map_id = message.map_id;
  keyframe.stamp_ns = message.stamp_ns;
  keyframe.T_wc = to_pose(message.T_wc);
  StereoFeatures& features = keyframe.features;
  features.pyramid = ScalePyramid::make(static_cast<int>(message.pyramid_levels), message.scale_factor);
  features.keypoints.resize(keypoints.size());
  features.descriptors.resize(keypoints.size());
  features.u_right_px.resize(keypoints.size());
  features.depth_m.resize(keypoints.size());
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const msg::KeyframeKeypoint& kp = keypoints[i];
    features.keypoints[i] = Keypoint{kp.u_px, kp.v_px, kp.angle_deg, 0.f, kp.octave};
    features.u_right_px[i] = kp.u_right_px;
    features.depth_m[i] = kp.depth_m;
    std::memcpy(features.descriptors[i].data(), descriptors.data() + i * kDescriptorBytes, kDescriptorBytes);
  }
  keyframe.point_ids.assign(point_ids.begin(), point_ids.end());
  for (const msg::NewStereoPoint& entry : runtime::view(message.new_points)) {
    MapPoint point;
    point.id = entry.id;
    point.map_id = keyframe.map_id;
    point.p_w = Eigen::Vector3d(entry.position_w_m[0], entry.position_w_m[1], entry.position_w_m[2]);
    point.reference_kf = keyframe.id;
    point.observations.emplace_back(keyframe.id, static_cast<int>(entry.keypoint_index));
    decoded.new_points.push_back(std::move(point));
  }
  return decoded;
}

}  // namespace heslam::messages

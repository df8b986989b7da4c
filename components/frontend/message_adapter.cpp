// IDL samples <-> core types for the frontend and the recorder (see the header for the contract).
#include "components/frontend/message_adapter.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "components/core/camera/image_limits.hpp"
#include "components/frontend/message_checks.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam::frontend {
namespace {

// IDL string<31>: 31 characters and the terminating zero.
constexpr std::size_t kStageNameCapacity = sizeof(msg::StageTime{}.stage);
// Every topic type carries at most this many stage times (IDL sequence<StageTime, 16>).
constexpr std::size_t kMaxStageTimes = 16;
constexpr std::size_t kDescriptorBytes = sizeof(Descriptor);

template <typename Matrix, std::size_t N>
void from_row_major(const double (&values)[N], Matrix& matrix) {
  std::size_t i = 0;
  for (int r = 0; r < matrix.rows(); ++r)
    for (int c = 0; c < matrix.cols(); ++c) matrix(r, c) = values[i++];
}

CameraModel to_camera_model(const msg::CameraModel& message, const std::string& source, const char* which) {
  if (!image_size_plausible(message.width_px, message.height_px)) {
    throw std::runtime_error("calibration '" + source + "': " + which + ": image size " +
                             std::to_string(message.width_px) + "x" + std::to_string(message.height_px) + ": " +
                             image_size_expectation());
  }
  CameraModel camera;
  camera.width_px = static_cast<int>(message.width_px);
  camera.height_px = static_cast<int>(message.height_px);
  camera.fx_px = message.fx_px;
  camera.fy_px = message.fy_px;
  camera.cx_px = message.cx_px;
  camera.cy_px = message.cy_px;
  if (camera.width_px <= 0 || camera.height_px <= 0 || camera.fx_px <= 0.0 || camera.fy_px <= 0.0) {
    throw std::runtime_error("calibration '" + source + "': " + which +
                             ": expected a positive image size and focal length");
  }
  switch (runtime::wire_value(message.distortion_model)) {  // any value may come (runtime/wire_enum.hpp)
    case heslam_msg_DISTORTION_NONE: camera.distortion_model = DistortionModel::kNone; break;
    case heslam_msg_DISTORTION_RADIAL_TANGENTIAL: camera.distortion_model = DistortionModel::kRadialTangential; break;
    default:
      throw std::runtime_error("calibration '" + source + "': " + which + ".distortion_model: unknown value " +
                               std::to_string(runtime::wire_value(message.distortion_model)));
  }
  const auto distortion = runtime::view(message.distortion);
  camera.distortion.assign(distortion.begin(), distortion.end());
  Eigen::Matrix4d T_BS;
  from_row_major(message.T_BS, T_BS);
  camera.T_BS.matrix() = T_BS;
  return camera;
}

// Removes the point from every keyframe that observes it; with a replacement (a merge) the keyframe
// sees the replacement instead, and the replacement gets the observation.
void replace_in_keyframes(Map& map, const MapPoint& point, MapPoint* replacement) {
  for (const auto& [keyframe_id, keypoint_index] : point.observations) {
    Keyframe* keyframe = map.keyframe(keyframe_id);
    if (keyframe == nullptr || keypoint_index < 0 ||
        static_cast<std::size_t>(keypoint_index) >= keyframe->point_ids.size() ||
        keyframe->point_ids[keypoint_index] != point.id) {
      continue;
    }
    keyframe->point_ids[keypoint_index] = replacement != nullptr ? replacement->id : kNoId;
    if (replacement == nullptr) continue;
    const std::pair<KeyframeId, int> observation{keyframe_id, keypoint_index};
    auto& observations = replacement->observations;
    if (std::find(observations.begin(), observations.end(), observation) == observations.end()) {
      observations.push_back(observation);
    }
  }
}

}  // namespace

msg::Pose to_message(const Pose3& T_ab) {
  msg::Pose pose{};
  const Eigen::Vector3d t = T_ab.translation();
  const Eigen::Quaterniond q(Eigen::Matrix3d(T_ab.linear()));
  for (int i = 0; i < 3; ++i) pose.position_m[i] = t[i];
  pose.orientation_xyzw[0] = q.x();
  pose.orientation_xyzw[1] = q.y();
  pose.orientation_xyzw[2] = q.z();
  pose.orientation_xyzw[3] = q.w();
  return pose;
}

Pose3 to_pose(const msg::Pose& pose) {
  Eigen::Quaterniond q(pose.orientation_xyzw[3], pose.orientation_xyzw[0], pose.orientation_xyzw[1],
                       pose.orientation_xyzw[2]);
  const double norm = q.norm();
  if (!(norm > 0.0)) q = Eigen::Quaterniond::Identity();  // an all-zero pose is "no pose": identity
  else q.coeffs() /= norm;
  Pose3 T = Pose3::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Vector3d(pose.position_m[0], pose.position_m[1], pose.position_m[2]);
  return T;
}

StereoCalibration to_calibration(const msg::StereoCalibration& message) {
  StereoCalibration calibration;
  calibration.source = runtime::to_string(message.source);
  const std::string source = calibration.source.empty() ? "<unnamed>" : calibration.source;
  calibration.left = to_camera_model(message.left, source, "left");
  calibration.right = to_camera_model(message.right, source, "right");
  calibration.input_rectified = message.input_rectified;
  if (message.has_explicit_rectification) {
    ExplicitRectification rectification;
    from_row_major(message.explicit_rectification.R_left, rectification.R_left);
    from_row_major(message.explicit_rectification.R_right, rectification.R_right);
    from_row_major(message.explicit_rectification.P_left, rectification.P_left);
    from_row_major(message.explicit_rectification.P_right, rectification.P_right);
    calibration.explicit_rectification = rectification;
  }
  calibration.rate_hz = message.rate_hz;
  return calibration;
}

PinholeStereo to_camera(const msg::RectifiedStereoCamera& message) {
  PinholeStereo camera;
  camera.fx_px = message.fx_px;
  camera.fy_px = message.fy_px;
  camera.cx_px = message.cx_px;
  camera.cy_px = message.cy_px;
  camera.baseline_m = message.baseline_m;
  camera.width_px = static_cast<int>(message.width_px);
  camera.height_px = static_cast<int>(message.height_px);
  return camera;
}

msg::RectifiedStereoCamera to_message(const PinholeStereo& camera) {
  msg::RectifiedStereoCamera message{};
  message.fx_px = camera.fx_px;
  message.fy_px = camera.fy_px;
  message.cx_px = camera.cx_px;
  message.cy_px = camera.cy_px;
  message.baseline_m = camera.baseline_m;
  message.width_px = static_cast<std::uint32_t>(camera.width_px);
  message.height_px = static_cast<std::uint32_t>(camera.height_px);
  return message;
}

GreyPair to_grey_images(const msg::StereoFrame& frame) {
  if (auto problem = check(frame)) throw std::runtime_error("stereo frame " + std::to_string(frame.seq) + ": " + *problem);
  const int width = static_cast<int>(frame.width_px);
  const int height = static_cast<int>(frame.height_px);
  const int channels = frame.encoding == heslam_msg_ENCODING_BGR8 ? 3 : 1;
  const auto left = runtime::view(frame.left);
  const auto right = runtime::view(frame.right);
  const int type = channels == 1 ? CV_8UC1 : CV_8UC3;
  // cv::Mat wraps non-const data; the pixels are only read.
  cv::Mat left_raw(height, width, type, const_cast<std::uint8_t*>(left.data()));
  cv::Mat right_raw(height, width, type, const_cast<std::uint8_t*>(right.data()));
  GreyPair pair;
  if (channels == 1) {
    pair.left = left_raw;
    pair.right = right_raw;
  } else {
    cv::cvtColor(left_raw, pair.left, cv::COLOR_BGR2GRAY);
    cv::cvtColor(right_raw, pair.right, cv::COLOR_BGR2GRAY);
  }
  return pair;
}

heslam_msg_TrackingState to_message(TrackingState state) {
  switch (state) {
    case TrackingState::kOk: return heslam_msg_TRACKING_OK;
    case TrackingState::kLost: return heslam_msg_TRACKING_LOST;
    case TrackingState::kNotInitialized: break;
  }
  return heslam_msg_TRACKING_NOT_INITIALIZED;
}

OdometryMessage::OdometryMessage(std::int64_t stamp_ns, std::uint64_t seq, const TrackResult& result,
                                 std::uint32_t keypoints, const std::vector<StageTiming>& timings) {
  message_.stamp_ns = stamp_ns;
  message_.seq = seq;
  message_.state = to_message(result.state);
  // Never a garbage pose: a frame that is not tracked carries the identity, and its state says so.
  message_.T_wc = to_message(result.pose_valid() ? result.T_wc : Pose3::Identity());
  message_.reference_keyframe_id = result.pose_valid() ? result.reference_kf : kNoId;
  message_.T_ref_c = to_message(result.pose_valid() ? result.T_ref_c : Pose3::Identity());
  message_.keypoints = keypoints;
  message_.tracked_points = static_cast<std::uint32_t>(std::max(0, result.tracked_points));
  message_.keyframe_created = result.new_keyframe.has_value();
  const std::size_t count = std::min(timings.size(), kMaxStageTimes);
  stage_times_.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    msg::StageTime& entry = stage_times_[i];
    std::memset(entry.stage, 0, kStageNameCapacity);
    std::memcpy(entry.stage, timings[i].stage.data(), std::min(timings[i].stage.size(), kStageNameCapacity - 1));
    entry.ms = static_cast<float>(timings[i].ms);
  }
  runtime::borrow(message_.stage_times, stage_times_);
}

KeyframeMessage::KeyframeMessage(const Keyframe& keyframe, std::uint64_t frame_seq,
                                 const std::vector<MapPoint>& new_points, const PinholeStereo& camera,
                                 KeyframeId reference_kf, std::uint64_t tracked_map_version) {
  const StereoFeatures& features = keyframe.features;
  message_.id = keyframe.id;
  message_.stamp_ns = keyframe.stamp_ns;
  message_.frame_seq = frame_seq;
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
    point.p_w = Eigen::Vector3d(entry.position_w_m[0], entry.position_w_m[1], entry.position_w_m[2]);
    point.reference_kf = keyframe.id;
    point.observations.emplace_back(keyframe.id, static_cast<int>(entry.keypoint_index));
    decoded.new_points.push_back(std::move(point));
  }
  return decoded;
}

bool is_version_marker(const msg::KeyframeState& state) { return state.id == kVersionMarkerId; }
bool is_version_marker(const msg::MapPointState& state) { return state.id == kVersionMarkerId; }

bool apply_keyframe_state(Map& map, const msg::KeyframeState& state) {
  Keyframe* keyframe = map.keyframe(state.id);
  if (keyframe == nullptr) return false;
  keyframe->T_wc = to_pose(state.T_wc);
  keyframe->parent = state.parent_id;
  keyframe->covisible.clear();
  for (const msg::CovisibleKeyframe& neighbour : runtime::view(state.covisible)) {
    keyframe->covisible.emplace_back(neighbour.id, static_cast<int>(neighbour.weight));
  }
  keyframe->culled = state.culled;
  return true;  // a culled keyframe stays (flagged) so frames referencing it keep their anchor

}

void apply_point_state(Map& map, const msg::MapPointState& state) {
  if (state.merged_into != kNoId) {
    erase_point(map, state.id, state.merged_into);
    return;
  }
  MapPoint& point = map.points[state.id];  // creates it when the mapper made it (triangulation)
  point.id = state.id;
  point.p_w = Eigen::Vector3d(state.position_w_m[0], state.position_w_m[1], state.position_w_m[2]);
  std::memcpy(point.descriptor.data(), state.descriptor, kDescriptorBytes);
  point.normal = Eigen::Vector3d(state.normal_w[0], state.normal_w[1], state.normal_w[2]);
  point.min_distance_m = state.min_distance_m;
  point.max_distance_m = state.max_distance_m;
  point.reference_kf = state.reference_keyframe_id;
  point.culled = state.culled;  // the tracker's searches skip culled points
  point.merged_into = kNoId;
  point.observations.clear();
  for (const msg::PointObservation& observation : runtime::view(state.observations)) {
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

}  // namespace heslam::frontend

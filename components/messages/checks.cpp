// Sample checks for every subscribed topic type (see the header).
#include "components/messages/checks.hpp"

#include <cmath>
#include <cstdint>
#include <sstream>

#include "components/core/camera/image_limits.hpp"
#include "components/core/map/ids.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam::messages {
namespace {

// Farther than any recording reaches (KITTI's longest drive is ~5 km): a larger coordinate is a
// garbage number, and would wreck an optimization as badly as a NaN.
constexpr double kMaxCoordinate_m = 1e6;
// Writers send unit quaternions (from a rotation matrix); anything far from unit length was not
// written by heslam. Zero is accepted: an all-zero pose reads as "no pose" (identity, to_pose).
constexpr double kQuaternionNormTolerance = 0.1;
// ORB pyramids have 8 levels; far more is a corrupt field (ScalePyramid would allocate per level).
constexpr std::uint32_t kMaxPyramidLevels = 32;
constexpr std::size_t kDescriptorBytes = 32;

template <typename... Parts>
std::string text(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

template <typename Number>
std::optional<std::string> finite(Number value, const std::string& field) {
  if (std::isfinite(static_cast<double>(value))) return std::nullopt;
  return text(field, " is ", value, ", expected a finite number");
}

template <typename Number>
std::optional<std::string> finite_coordinates(const Number* values, int count, const std::string& field) {
  for (int i = 0; i < count; ++i) {
    const std::string name = text(field, "[", i, "]");
    if (auto problem = finite(values[i], name)) return problem;
    if (std::abs(static_cast<double>(values[i])) > kMaxCoordinate_m) {
      return text(name, " is ", values[i], ", expected at most ", kMaxCoordinate_m, " m in magnitude");
    }
  }
  return std::nullopt;
}

std::optional<std::string> check_rectified(const msg::RectifiedStereoCamera& camera, const std::string& field) {
  for (const auto& [value, name] :
       {std::pair{camera.fx_px, "fx_px"}, std::pair{camera.fy_px, "fy_px"}, std::pair{camera.cx_px, "cx_px"},
        std::pair{camera.cy_px, "cy_px"}, std::pair{camera.baseline_m, "baseline_m"}}) {
    if (auto problem = finite(value, field + "." + name)) return problem;
  }
  return std::nullopt;
}

std::optional<std::string> check_camera_model(const msg::CameraModel& camera, const std::string& field) {
  for (const auto& [value, name] : {std::pair{camera.fx_px, "fx_px"}, std::pair{camera.fy_px, "fy_px"},
                                    std::pair{camera.cx_px, "cx_px"}, std::pair{camera.cy_px, "cy_px"}}) {
    if (auto problem = finite(value, field + "." + name)) return problem;
  }
  for (double value : runtime::view(camera.distortion)) {
    if (auto problem = finite(value, field + ".distortion")) return problem;
  }
  for (double value : camera.T_BS) {
    if (auto problem = finite(value, field + ".T_BS")) return problem;
  }
  return std::nullopt;
}

template <std::size_t N>
std::optional<std::string> check_matrix(const double (&values)[N], const std::string& field) {
  for (double value : values) {
    if (auto problem = finite(value, field)) return problem;
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> check(const msg::Pose& pose, const char* field) {
  if (auto problem = finite_coordinates(pose.position_m, 3, text(field, ".position_m"))) return problem;
  double norm_squared = 0.0;
  for (int i = 0; i < 4; ++i) {
    if (auto problem = finite(pose.orientation_xyzw[i], text(field, ".orientation_xyzw[", i, "]"))) return problem;
    norm_squared += pose.orientation_xyzw[i] * pose.orientation_xyzw[i];
  }
  const double norm = std::sqrt(norm_squared);
  if (norm != 0.0 && std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    return text(field, ".orientation_xyzw has norm ", norm, ", expected a unit quaternion");
  }
  return std::nullopt;
}

std::optional<std::string> check(const msg::StereoFrame& frame) {
  // Checked as the unsigned wire values: 0xFFFFFFFF must read as 4294967295, not as -1.
  if (!image_size_plausible(frame.width_px, frame.height_px)) {
    return text("width_px x height_px ", frame.width_px, "x", frame.height_px, ": ", image_size_expectation());
  }
  std::size_t channels = 0;
  // Enum fields are read as the integers on the wire (runtime/wire_enum.hpp): any value may come.
  switch (runtime::wire_value(frame.encoding)) {
    case heslam_msg_ENCODING_MONO8: channels = 1; break;
    case heslam_msg_ENCODING_BGR8: channels = 3; break;
    default: return text("unknown encoding ", runtime::wire_value(frame.encoding));
  }
  const std::size_t expected = std::size_t{frame.width_px} * frame.height_px * channels;
  const std::size_t left = frame.left._length;
  const std::size_t right = frame.right._length;
  if (left == expected && right == expected) return std::nullopt;
  // Name the side that is wrong (both when both are).
  std::string got;
  if (left != expected) got += text("left has ", left);
  if (right != expected) got += text(got.empty() ? "" : ", ", "right has ", right);
  return text("expected ", expected, " bytes per image for ", frame.width_px, "x", frame.height_px, "x", channels, ", ",
              got);
}

std::optional<std::string> check(const msg::StereoCalibration& calibration) {
  if (auto problem = check_camera_model(calibration.left, "left")) return problem;
  if (auto problem = check_camera_model(calibration.right, "right")) return problem;
  if (calibration.has_explicit_rectification) {
    const msg::ExplicitRectification& r = calibration.explicit_rectification;
    if (auto problem = check_matrix(r.R_left, "explicit_rectification.R_left")) return problem;
    if (auto problem = check_matrix(r.R_right, "explicit_rectification.R_right")) return problem;
    if (auto problem = check_matrix(r.P_left, "explicit_rectification.P_left")) return problem;
    if (auto problem = check_matrix(r.P_right, "explicit_rectification.P_right")) return problem;
  }
  if (auto problem = check_rectified(calibration.rectified, "rectified")) return problem;
  return finite(calibration.rate_hz, "rate_hz");
}

std::optional<std::string> check(const msg::Odometry& odometry) {
  if (!runtime::wire_value_is_one_of(odometry.state, heslam_msg_TRACKING_NOT_INITIALIZED, heslam_msg_TRACKING_OK,
                                     heslam_msg_TRACKING_LOST, heslam_msg_TRACKING_INERTIAL_ONLY)) {
    return text("state ", runtime::wire_value(odometry.state), " is not a TrackingState");
  }
  if (auto problem = check(odometry.T_wc, "T_wc")) return problem;
  return check(odometry.T_ref_c, "T_ref_c");
}

std::optional<std::string> check(const msg::Keyframe& keyframe) {
  if (keyframe.id == 0) return std::string("id is 0 (no keyframe)");
  const std::string name = text("keyframe ", format_id(keyframe.id), ": ");
  if (auto problem = check(keyframe.T_wc, "T_wc")) return name + *problem;
  if (auto problem = check_rectified(keyframe.camera, "camera")) return name + *problem;
  if (!(keyframe.camera.fx_px > 0.0) || !(keyframe.camera.fy_px > 0.0))
    return name + "camera focal length is not positive";
  if (keyframe.pyramid_levels < 1 || keyframe.pyramid_levels > kMaxPyramidLevels) {
    return text(name, "pyramid_levels ", keyframe.pyramid_levels, ", expected 1..", kMaxPyramidLevels);
  }
  if (!(keyframe.scale_factor >= 1.0f) || !std::isfinite(keyframe.scale_factor)) {
    return text(name, "scale_factor ", keyframe.scale_factor, ", expected a finite number >= 1");
  }
  const auto keypoints = runtime::view(keyframe.keypoints);
  if (keyframe.descriptors._length != keypoints.size() * kDescriptorBytes ||
      keyframe.point_ids._length != keypoints.size()) {
    return text(name, keypoints.size(), " keypoints but ", keyframe.descriptors._length, " descriptor bytes and ",
                keyframe.point_ids._length, " point ids");
  }
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const msg::KeyframeKeypoint& kp = keypoints[i];
    const float values[] = {kp.u_px, kp.v_px, kp.u_right_px, kp.depth_m, kp.angle_deg};
    if (auto problem = finite_coordinates(values, 5, text("keypoints[", i, "] (u, v, u_right, depth, angle)"))) {
      return name + *problem;
    }
    if (kp.octave < 0 || static_cast<std::uint32_t>(kp.octave) >= keyframe.pyramid_levels) {
      return text(name, "keypoints[", i, "].octave ", kp.octave, ", expected 0..", keyframe.pyramid_levels - 1);
    }
  }
  for (const msg::NewStereoPoint& point : runtime::view(keyframe.new_points)) {
    if (point.id == 0) return name + "a new point has id 0";
    if (point.keypoint_index >= keypoints.size()) {
      return text(name, "new point ", format_id(point.id), ": keypoint_index ", point.keypoint_index, " of ",
                  keypoints.size());
    }
    if (auto problem =
            finite_coordinates(point.position_w_m, 3, text("new point ", format_id(point.id), " position_w_m"))) {
      return name + *problem;
    }
  }
  return std::nullopt;
}

std::optional<std::string> check(const msg::KeyframeState& state) {
  if (state.id == 0) return std::nullopt;  // a version marker: only map_version is read
  const std::string name = text("keyframe state ", format_id(state.id), ": ");
  if (auto problem = check(state.T_wc, "T_wc")) return name + *problem;
  for (const msg::CovisibleKeyframe& neighbour : runtime::view(state.covisible)) {
    if (neighbour.id == 0) return name + "a covisible keyframe has id 0";
  }
  return std::nullopt;
}

std::optional<std::string> check(const msg::MapPointState& point) {
  if (point.id == 0) return std::nullopt;  // a version marker
  const std::string name = text("point ", format_id(point.id), ": ");
  if (auto problem = finite_coordinates(point.position_w_m, 3, "position_w_m")) return name + *problem;
  if (auto problem = finite_coordinates(point.normal_w, 3, "normal_w")) return name + *problem;
  const float distances[] = {point.min_distance_m, point.max_distance_m};
  if (auto problem = finite_coordinates(distances, 2, "(min, max)_distance_m")) return name + *problem;
  for (const msg::PointObservation& observation : runtime::view(point.observations)) {
    if (observation.keyframe_id == 0) return name + "an observation has keyframe id 0";
  }
  return std::nullopt;
}

std::optional<std::string> check(const msg::LoopCorrection& correction) {
  if (correction.id == 0) return std::string("id is 0 (no correction)");
  const std::string name = text("correction ", format_id(correction.id), ": ");
  if (!runtime::wire_value_is_one_of(correction.kind, heslam_msg_CORRECTION_LOOP, heslam_msg_CORRECTION_GLOBAL_BA,
                                     heslam_msg_CORRECTION_MERGE)) {
    return text(name, "kind ", runtime::wire_value(correction.kind), " is not a CorrectionKind");
  }
  if (auto problem = check(correction.T_matched_loop, "T_matched_loop")) return name + *problem;
  for (const msg::CorrectedKeyframePose& pose : runtime::view(correction.corrected_poses)) {
    if (pose.keyframe_id == 0) return name + "a corrected pose has keyframe id 0";
    if (auto problem = check(pose.T_wc, "corrected_poses.T_wc"))
      return text(name, "keyframe ", format_id(pose.keyframe_id), ": ", *problem);
  }
  for (const msg::PointMerge& merge : runtime::view(correction.point_merges)) {
    if (merge.from_id == 0 || merge.into_id == 0) return name + "a point merge has id 0";
  }
  for (const msg::CorrectedPointPosition& point : runtime::view(correction.corrected_points)) {
    if (auto problem = finite_coordinates(point.position_w_m, 3,
                                          text("corrected point ", format_id(point.point_id), " position_w_m"))) {
      return name + *problem;
    }
  }
  return std::nullopt;
}

const char* rejected_counter(const msg::StereoCalibration*) { return "rejected_calibrations"; }
const char* rejected_counter(const msg::Odometry*) { return "rejected_odometry"; }
const char* rejected_counter(const msg::Keyframe*) { return "rejected_keyframes"; }
const char* rejected_counter(const msg::KeyframeState*) { return "rejected_keyframe_states"; }
const char* rejected_counter(const msg::MapPointState*) { return "rejected_points"; }
const char* rejected_counter(const msg::LoopCorrection*) { return "rejected_corrections"; }

}  // namespace heslam::messages

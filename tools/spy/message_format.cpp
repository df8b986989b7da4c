// YAML-like text of the project messages for heslam-spy echo.
#include "tools/spy/message_format.hpp"

#include <algorithm>

#include <cstdio>
#include <functional>
#include <span>
#include <sstream>

#include "components/core/map/ids.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam {

namespace {

// Summary mode shows this many elements of a long sequence: enough to see the shape of the data.
constexpr std::size_t kPreviewElements = 3;
// Full mode prints raw bytes (images, descriptors) in rows of this many.
constexpr std::size_t kBytesPerRow = 32;

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", value);
  return text;
}

template <typename T, std::size_t N>
std::string array(const T (&values)[N]) {
  std::string text = "[";
  for (std::size_t i = 0; i < N; ++i) text += (i ? ", " : "") + number(static_cast<double>(values[i]));
  return text + "]";
}

// Writes "key: value" lines with indentation.
class Text {
 public:
  void line(int indent, const std::string& key, const std::string& value) {
    out_ << std::string(2 * indent, ' ') << key << ": " << value << '\n';
  }
  void header(int indent, const std::string& key) { out_ << std::string(2 * indent, ' ') << key << ":\n"; }
  void item(int indent, const std::string& value) { out_ << std::string(2 * indent, ' ') << "- " << value << '\n'; }
  std::string str() const { return out_.str(); }

 private:
  std::ostringstream out_;
};

// A sequence: its length, then every element (full) or the first few.
template <typename Element>
void sequence(Text& text, int indent, const std::string& key, std::span<const Element> values,
              const FormatOptions& options, const std::function<std::string(const Element&)>& format) {
  const std::size_t shown = options.full ? values.size() : std::min(values.size(), kPreviewElements);
  text.line(indent, key + "_count", std::to_string(values.size()));
  if (values.empty()) return;
  text.header(indent, key);
  for (std::size_t i = 0; i < shown; ++i) text.item(indent + 1, format(values[i]));
  if (shown < values.size()) text.item(indent + 1, "... (" + std::to_string(values.size() - shown) + " more, --full)");
}

void bytes(Text& text, int indent, const std::string& key, std::span<const std::uint8_t> values) {
  text.header(indent, key);
  for (std::size_t row = 0; row < values.size(); row += kBytesPerRow) {
    std::string hex;
    char byte[4];
    for (std::size_t i = row; i < std::min(values.size(), row + kBytesPerRow); ++i) {
      std::snprintf(byte, sizeof(byte), "%02x", values[i]);
      hex += byte;
    }
    text.item(indent + 1, hex);
  }
}

// The local mapper ends each batch of state samples with a sample of this id on both state topics
// (kVersionMarkerId, components/messages/map_state.hpp; docs/topics.md): no keyframe or point.
constexpr std::uint64_t kVersionMarkerId = 0;

std::string version_marker(std::uint64_t map_version) {
  Text text;
  text.line(0, "version_marker",
            "end of the local mapper's batch of map version " + std::to_string(map_version) +
                " (id 0: no keyframe or point)");
  text.line(0, "map_version", std::to_string(map_version));
  return text.str();
}

// Odometry's T_wc is the tracker's: the rectified left camera, optical axes, in the map's world frame.
// The recorder's trajectory file holds another frame by default (--frame body, docs/recorder.md).
constexpr const char* kOdometryFrame =
    "rectified left camera (optical: x right, y down, z forward) in the map's world frame; "
    "the recorder's file holds --frame (default body: T_wb)";

std::string pose(const msg::Pose& value) {
  return "{position_m: " + array(value.position_m) + ", orientation_xyzw: " + array(value.orientation_xyzw) + "}";
}

std::string camera(const msg::RectifiedStereoCamera& value) {
  return "{fx_px: " + number(value.fx_px) + ", fy_px: " + number(value.fy_px) + ", cx_px: " + number(value.cx_px) +
         ", cy_px: " + number(value.cy_px) + ", baseline_m: " + number(value.baseline_m) +
         ", size: " + std::to_string(value.width_px) + "x" + std::to_string(value.height_px) + "}";
}

// Enum fields are shown from their wire integers (runtime/wire_enum.hpp): a spied sample may hold
// a value of no enumerator, shown as "unknown".
const char* encoding_name(const heslam_msg_ImageEncoding& field) {
  switch (runtime::wire_value(field)) {
    case heslam_msg_ENCODING_MONO8: return "mono8";
    case heslam_msg_ENCODING_BGR8: return "bgr8";
  }
  return "unknown";
}

std::string distortion_name(std::int64_t value) {
  switch (value) {
    case heslam_msg_DISTORTION_NONE: return "none";
    case heslam_msg_DISTORTION_RADIAL_TANGENTIAL: return "radtan";
    case heslam_msg_DISTORTION_EQUIDISTANT: return "equidistant";
    default: return "unknown(" + std::to_string(value) + ")";
  }
}

std::string raw_camera(const msg::CameraModel& value) {
  std::string distortion = "[";
  const auto coefficients = runtime::view(value.distortion);
  for (std::size_t i = 0; i < coefficients.size(); ++i) distortion += (i ? ", " : "") + number(coefficients[i]);
  distortion += "]";
  return "{size: " + std::to_string(value.width_px) + "x" + std::to_string(value.height_px) +
         ", fx_px: " + number(value.fx_px) + ", fy_px: " + number(value.fy_px) + ", cx_px: " + number(value.cx_px) +
         ", cy_px: " + number(value.cy_px) +
         ", distortion: " + distortion_name(runtime::wire_value(value.distortion_model)) + " " + distortion +
         ", T_BS: " + array(value.T_BS) + "}";
}

}  // namespace

double mean_intensity(const msg::StereoFrame& frame, bool right) {
  const auto pixels = runtime::view(right ? frame.right : frame.left);
  if (pixels.empty()) return 0.0;
  std::uint64_t sum = 0;
  for (const std::uint8_t value : pixels) sum += value;
  return static_cast<double>(sum) / static_cast<double>(pixels.size());
}

std::string format_message(const msg::StereoFrame& frame, const FormatOptions& options) {
  Text text;
  text.line(0, "seq", std::to_string(frame.seq));
  text.line(0, "stamp_ns", std::to_string(frame.stamp_ns));
  text.line(0, "stamp_right_ns", std::to_string(frame.stamp_right_ns));
  text.line(
      0, "size",
      std::to_string(frame.width_px) + "x" + std::to_string(frame.height_px) + " " + encoding_name(frame.encoding));
  char mean[64];
  std::snprintf(mean, sizeof(mean), "%.2f / %.2f", mean_intensity(frame, false), mean_intensity(frame, true));
  text.line(0, "mean_intensity_left_right", mean);
  text.line(0, "bytes_left_right", std::to_string(frame.left._length) + " / " + std::to_string(frame.right._length));
  if (options.full) {
    bytes(text, 0, "left", runtime::view(frame.left));
    bytes(text, 0, "right", runtime::view(frame.right));
  }
  return text.str();
}

std::string format_message(const msg::StereoCalibration& calibration, const FormatOptions& /*options*/) {
  Text text;
  text.line(0, "source", runtime::to_string(calibration.source));
  text.line(0, "input_rectified", calibration.input_rectified ? "true" : "false");
  text.line(0, "rate_hz", number(calibration.rate_hz));
  text.line(0, "left", raw_camera(calibration.left));
  text.line(0, "right", raw_camera(calibration.right));
  if (calibration.has_explicit_rectification) {
    const msg::ExplicitRectification& r = calibration.explicit_rectification;
    text.header(0, "explicit_rectification");
    text.line(1, "R_left", array(r.R_left));
    text.line(1, "R_right", array(r.R_right));
    text.line(1, "P_left", array(r.P_left));
    text.line(1, "P_right", array(r.P_right));
  }
  text.line(0, "rectified", camera(calibration.rectified));
  return text.str();
}

std::string format_message(const msg::Odometry& odometry, const FormatOptions& options) {
  Text text;
  const std::int64_t tracking = runtime::wire_value(odometry.state);
  const char* state = tracking == heslam_msg_TRACKING_OK                ? "OK"
                      : tracking == heslam_msg_TRACKING_LOST            ? "LOST"
                      : tracking == heslam_msg_TRACKING_INERTIAL_ONLY   ? "INERTIAL_ONLY"
                      : tracking == heslam_msg_TRACKING_NOT_INITIALIZED ? "NOT_INITIALIZED"
                                                                        : "unknown";
  text.line(0, "seq", std::to_string(odometry.seq));
  text.line(0, "stamp_ns", std::to_string(odometry.stamp_ns));
  text.line(0, "state", state);
  text.line(0, "map_id", std::to_string(odometry.map_id));
  text.line(0, "T_wc", pose(odometry.T_wc));
  text.line(0, "T_wc_frame", kOdometryFrame);
  text.line(0, "reference_keyframe_id", format_id(odometry.reference_keyframe_id));
  text.line(0, "T_ref_c", pose(odometry.T_ref_c));
  text.line(0, "T_oc", pose(odometry.T_oc));
  // The covariance's diagonal (rotation x y z in rad^2, position x y z in m^2); all zero: not known.
  const double* covariance = odometry.T_wc_covariance;
  const bool has_covariance = std::any_of(covariance, covariance + 21, [](double value) { return value != 0.0; });
  if (has_covariance) {
    // Upper triangle row by row: the diagonal of row r sits at r * 6 - r * (r - 1) / 2.
    std::string diagonal = "[";
    for (int row = 0; row < 6; ++row) {
      diagonal += (row > 0 ? ", " : "") + number(covariance[row * 6 - row * (row - 1) / 2]);
    }
    text.line(0, "T_wc_covariance_diagonal", diagonal + "]");
  } else {
    text.line(0, "T_wc_covariance_diagonal", "unknown");
  }
  text.line(0, "v_w",
            odometry.velocity_valid
                ? "[" + number(odometry.v_w[0]) + ", " + number(odometry.v_w[1]) + ", " + number(odometry.v_w[2]) + "]"
                : "unknown");
  text.line(0, "keypoints", std::to_string(odometry.keypoints));
  text.line(0, "tracked_points", std::to_string(odometry.tracked_points));
  text.line(0, "keyframe_created", odometry.keyframe_created ? "true" : "false");
  FormatOptions all = options;
  all.full = true;  // at most 16 stages: always all of them
  sequence<msg::StageTime>(
      text, 0, "stage_times", runtime::view(odometry.stage_times), all,
      [](const msg::StageTime& stage) { return std::string(stage.stage) + ": " + number(stage.ms) + " ms"; });
  return text.str();
}

std::string format_message(const msg::Keyframe& keyframe, const FormatOptions& options) {
  Text text;
  text.line(0, "id", format_id(keyframe.id));
  text.line(0, "stamp_ns", std::to_string(keyframe.stamp_ns));
  text.line(0, "frame_seq", std::to_string(keyframe.frame_seq));
  text.line(0, "map_id", std::to_string(keyframe.map_id));
  text.line(0, "T_wc", pose(keyframe.T_wc));
  text.line(0, "reference_keyframe_id", format_id(keyframe.reference_keyframe_id));
  text.line(0, "tracked_map_version", std::to_string(keyframe.tracked_map_version));
  text.line(0, "camera", camera(keyframe.camera));
  text.line(0, "pyramid", std::to_string(keyframe.pyramid_levels) + " levels x " + number(keyframe.scale_factor));
  sequence<msg::KeyframeKeypoint>(
      text, 0, "keypoints", runtime::view(keyframe.keypoints), options, [](const msg::KeyframeKeypoint& k) {
        return "{u_px: " + number(k.u_px) + ", v_px: " + number(k.v_px) + ", u_right_px: " + number(k.u_right_px) +
               ", depth_m: " + number(k.depth_m) + ", angle_deg: " + number(k.angle_deg) +
               ", octave: " + std::to_string(k.octave) + "}";
      });
  text.line(0, "descriptor_bytes", std::to_string(keyframe.descriptors._length));
  if (options.full) bytes(text, 0, "descriptors", runtime::view(keyframe.descriptors));
  std::size_t observed = 0;
  for (const std::uint64_t id : runtime::view(keyframe.point_ids)) observed += id != 0 ? 1 : 0;
  text.line(0, "observed_points", std::to_string(observed));
  if (options.full) {
    sequence<std::uint64_t>(text, 0, "point_ids", runtime::view(keyframe.point_ids), options,
                            [](const std::uint64_t& id) { return format_id(id); });
  }
  sequence<msg::NewStereoPoint>(
      text, 0, "new_points", runtime::view(keyframe.new_points), options, [](const msg::NewStereoPoint& p) {
        return "{id: " + format_id(p.id) + ", keypoint_index: " + std::to_string(p.keypoint_index) +
               ", position_w_m: " + array(p.position_w_m) + "}";
      });
  return text.str();
}

std::string format_message(const msg::KeyframeState& state, const FormatOptions& options) {
  Text text;
  if (state.id == kVersionMarkerId) return version_marker(state.map_version);
  text.line(0, "id", format_id(state.id));
  text.line(0, "map_version", std::to_string(state.map_version));
  text.line(0, "map_id", std::to_string(state.map_id));
  text.line(0, "T_wc", pose(state.T_wc));
  text.line(0, "parent_id", format_id(state.parent_id));
  text.line(0, "culled", state.culled ? "true" : "false");
  sequence<msg::CovisibleKeyframe>(text, 0, "covisible", runtime::view(state.covisible), options,
                                   [](const msg::CovisibleKeyframe& c) {
                                     return "{id: " + format_id(c.id) + ", weight: " + std::to_string(c.weight) + "}";
                                   });
  return text.str();
}

std::string format_message(const msg::MapPointState& point, const FormatOptions& options) {
  Text text;
  if (point.id == kVersionMarkerId) return version_marker(point.map_version);
  text.line(0, "id", format_id(point.id));
  text.line(0, "map_version", std::to_string(point.map_version));
  text.line(0, "map_id", std::to_string(point.map_id));
  text.line(0, "position_w_m", array(point.position_w_m));
  text.line(0, "normal_w", array(point.normal_w));
  text.line(0, "distance_range_m", "[" + number(point.min_distance_m) + ", " + number(point.max_distance_m) + "]");
  text.line(0, "reference_keyframe_id", format_id(point.reference_keyframe_id));
  text.line(0, "culled", point.culled ? "true" : "false");
  text.line(0, "merged_into", format_id(point.merged_into));
  if (options.full)
    bytes(text, 0, "descriptor", std::span<const std::uint8_t>(point.descriptor, sizeof(point.descriptor)));
  sequence<msg::PointObservation>(text, 0, "observations", runtime::view(point.observations), options,
                                  [](const msg::PointObservation& o) {
                                    return "{keyframe_id: " + format_id(o.keyframe_id) +
                                           ", keypoint_index: " + std::to_string(o.keypoint_index) + "}";
                                  });
  return text.str();
}

std::string format_message(const msg::LoopCorrection& correction, const FormatOptions& options) {
  Text text;
  text.line(0, "id", format_id(correction.id));
  text.line(0, "map_version", std::to_string(correction.map_version));
  text.line(0, "loop_keyframe_id", format_id(correction.loop_keyframe_id));
  text.line(0, "matched_keyframe_id", format_id(correction.matched_keyframe_id));
  text.line(0, "T_matched_loop", pose(correction.T_matched_loop));
  sequence<msg::CorrectedKeyframePose>(text, 0, "corrected_poses", runtime::view(correction.corrected_poses), options,
                                       [](const msg::CorrectedKeyframePose& c) {
                                         return "{keyframe_id: " + format_id(c.keyframe_id) +
                                                ", T_wc: " + pose(c.T_wc) + "}";
                                       });
  sequence<msg::PointMerge>(text, 0, "point_merges", runtime::view(correction.point_merges), options,
                            [](const msg::PointMerge& m) {
                              return "{from_id: " + format_id(m.from_id) + ", into_id: " + format_id(m.into_id) + "}";
                            });
  return text.str();
}

std::string format_message(const msg::FrameDone& done, const FormatOptions& /*options*/) {
  Text text;
  text.line(0, "seq", std::to_string(done.seq));
  text.line(0, "stamp_ns", std::to_string(done.stamp_ns));
  text.line(0, "component", runtime::to_string(done.component));
  text.line(0, "keyframe_created", done.keyframe_created ? "true" : "false");
  text.line(0, "keyframe_id", format_id(done.keyframe_id));
  return text.str();
}

std::string format_message(const msg::KeyframeDone& done, const FormatOptions& /*options*/) {
  Text text;
  text.line(0, "keyframe_id", format_id(done.keyframe_id));
  text.line(0, "component", runtime::to_string(done.component));
  text.line(0, "map_version", std::to_string(done.map_version));
  return text.str();
}

std::string format_message(const msg::ComponentStatus& status, const FormatOptions& options) {
  Text text;
  const std::int64_t component_state = runtime::wire_value(status.state);
  const char* state = component_state == heslam_msg_STATE_CONFIGURING     ? "CONFIGURING"
                      : component_state == heslam_msg_STATE_RUNNING       ? "RUNNING"
                      : component_state == heslam_msg_STATE_SHUTTING_DOWN ? "SHUTTING_DOWN"
                      : component_state == heslam_msg_STATE_FAILED        ? "FAILED"
                                                                          : "unknown";
  text.line(0, "name", runtime::to_string(status.name));
  text.line(0, "pid", std::to_string(status.pid));
  text.line(0, "executable", runtime::to_string(status.executable));
  text.line(0, "state", state);
  text.line(0, "uptime_s", number(status.uptime_s));
  text.line(0, "stamp_ns", std::to_string(status.stamp_ns));
  text.line(0, "rss_mib", number(static_cast<double>(status.rss_bytes) / (1024.0 * 1024.0)));
  FormatOptions all = options;
  all.full = true;  // a handful of counters and stages: always all of them
  sequence<msg::Counter>(text, 0, "counters", runtime::view(status.counters), all, [](const msg::Counter& c) {
    return runtime::to_string(c.name) + ": " + std::to_string(c.value);
  });
  sequence<msg::StageStats>(text, 0, "stages", runtime::view(status.stages), all, [](const msg::StageStats& s) {
    return runtime::to_string(s.name) + ": {count: " + std::to_string(s.count) + ", p50_ms: " + number(s.p50_ms) +
           ", p90_ms: " + number(s.p90_ms) + ", p99_ms: " + number(s.p99_ms) + ", max_ms: " + number(s.max_ms) + "}";
  });
  if (status.message != nullptr && status.message[0] != '\0') text.line(0, "message", status.message);
  return text.str();
}

// The IMU topics: a batch shows its continuity fields, then its readings (summary: the first few).
std::string format_message(const msg::ImuBatch& batch, const FormatOptions& options) {
  Text text;
  text.line(0, "seq", std::to_string(batch.seq));
  text.line(0, "first_index", std::to_string(batch.first_index));
  text.line(0, "watermark_ns", std::to_string(batch.watermark_ns));
  text.line(0, "end_of_stream", batch.end_of_stream ? "true" : "false");
  sequence<msg::ImuReading>(text, 0, "readings", runtime::view(batch.readings), options, [](const msg::ImuReading& r) {
    return "{stamp_ns: " + std::to_string(r.stamp_ns) + ", gyro_rad_s: " + array(r.gyro_rad_s) +
           ", accel_m_s2: " + array(r.accel_m_s2) + "}";
  });
  return text.str();
}

std::string format_message(const msg::ImuCalibration& calibration, const FormatOptions& /*options*/) {
  Text text;
  text.line(0, "T_BS", array(calibration.T_BS));
  text.line(0, "rate_hz", number(calibration.rate_hz));
  text.line(0, "gyroscope_noise_density", number(calibration.gyroscope_noise_density));
  text.line(0, "gyroscope_random_walk", number(calibration.gyroscope_random_walk));
  text.line(0, "accelerometer_noise_density", number(calibration.accelerometer_noise_density));
  text.line(0, "accelerometer_random_walk", number(calibration.accelerometer_random_walk));
  text.line(0, "time_offset_ns", std::to_string(calibration.time_offset_ns));
  text.line(0, "source", runtime::to_string(calibration.source));
  return text.str();
}

std::string format_message(const msg::OccupancyGrid2D& grid, const FormatOptions& /*options*/) {
  std::size_t occupied = 0, free = 0;
  for (std::uint32_t i = 0; i < grid.cells._length; ++i) {
    occupied += grid.cells._buffer[i] == heslam_msg_OCCUPANCY_OCCUPIED;
    free += grid.cells._buffer[i] == heslam_msg_OCCUPANCY_FREE;
  }
  Text text;
  text.line(0, "revision", std::to_string(grid.revision));
  text.line(0, "stamp_ns", std::to_string(grid.stamp_ns));
  text.line(0, "keyframes", std::to_string(grid.keyframes));
  text.line(0, "resolution_m", std::to_string(grid.resolution_m));
  text.line(0, "T_wg", pose(grid.T_wg));
  text.line(0, "origin", "[" + std::to_string(grid.origin_i) + ", " + std::to_string(grid.origin_j) + "]");
  text.line(0, "size", std::to_string(grid.width) + " x " + std::to_string(grid.height));
  text.line(0, "cells",
            std::to_string(grid.cells._length) + " (" + std::to_string(occupied) + " occupied, " +
                std::to_string(free) + " free)");
  return text.str();
}

std::string format_message(const msg::DenseCloud& cloud, const FormatOptions& /*options*/) {
  Text text;
  text.line(0, "revision", std::to_string(cloud.revision));
  text.line(0, "stamp_ns", std::to_string(cloud.stamp_ns));
  text.line(0, "keyframes", std::to_string(cloud.keyframes));
  text.line(0, "total_points", std::to_string(cloud.total_points));
  text.line(0, "points", std::to_string(cloud.xyz_w_m._length / 3));
  return text.str();
}

std::string format_message(const msg::OccupancySaveRequest& request, const FormatOptions& /*options*/) {
  Text text;
  text.line(0, "request_id", std::to_string(request.request_id));
  text.line(0, "output_stem", request.output_stem ? request.output_stem : "");
  return text.str();
}

std::string format_message(const msg::OccupancySaveReply& reply, const FormatOptions& /*options*/) {
  Text text;
  text.line(0, "request_id", std::to_string(reply.request_id));
  text.line(0, "ok", reply.ok ? "true" : "false");
  text.line(0, "output_stem", reply.output_stem ? reply.output_stem : "");
  text.line(0, "keyframes", std::to_string(reply.keyframes));
  text.line(0, "cells",
            std::to_string(reply.occupied_cells) + " occupied, " + std::to_string(reply.free_cells) + " free");
  text.line(0, "points", std::to_string(reply.points));
  text.line(0, "message", reply.message ? reply.message : "");
  return text.str();
}

}  // namespace heslam

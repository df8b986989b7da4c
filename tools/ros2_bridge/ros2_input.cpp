// heslam-ros2-input: ROS 2 camera topics in, heslam camera topics out (see ros2_input.hpp).
#include "tools/ros2_bridge/ros2_input.hpp"

#include <algorithm>
#include <cstring>
#include <span>
#include <stdexcept>

#include "components/core/camera/stereo_rectifier.hpp"
#include "runtime/run_counters.hpp"
#include "runtime/sequence.hpp"
#include "tools/replay/replay_messages.hpp"

namespace heslam::ros2 {

namespace {

// ROS 2's sensor data profile (rmw_qos_profile_sensor_data): best effort, volatile, keep last 5, what
// camera drivers publish with; a best-effort reader also matches a reliable driver.
constexpr int kSensorDataDepth = 5;
runtime::Qos sensor_data_qos() {
  return runtime::Qos(runtime::QosRole::kImages).best_effort().keep_last(kSensorDataDepth).volatile_durability();
}
// How long run() waits for heslam traffic before it polls the ROS 2 readers again: the most a frame
// waits in the reader before it is taken.
constexpr auto kPollPeriod = std::chrono::milliseconds(5);
constexpr double kMaxIdle_s = 3600.0;

const char* side_name(StereoPairer::Side side) { return side == StereoPairer::Side::kLeft ? "left" : "right"; }

void check_topic_name(const std::string& name, const char* field) {
  if (name.empty() || name.front() == '/' || name.back() == '/') {
    throw std::runtime_error(std::string(field) + ": '" + name +
                             "': expected a ROS 2 topic name without leading or trailing '/' (e.g. "
                             "stereo/left/image_raw)");
  }
}

}  // namespace

InputOptions InputOptions::from(const runtime::Config& config) {
  InputOptions options;
  options.left_image_topic = config.get_string("left_image_topic", options.left_image_topic);
  options.right_image_topic = config.get_string("right_image_topic", options.right_image_topic);
  options.left_info_topic = config.get_string("left_info_topic", options.left_info_topic);
  options.right_info_topic = config.get_string("right_info_topic", options.right_info_topic);
  options.images_rectified = config.get_choice("images", "raw", {"raw", "rectified"}) == "rectified";
  options.end_after_idle_s = config.get_double("end_after_idle_s", options.end_after_idle_s, 0.0, kMaxIdle_s);
  check_topic_name(options.left_image_topic, "left_image_topic");
  check_topic_name(options.right_image_topic, "right_image_topic");
  check_topic_name(options.left_info_topic, "left_info_topic");
  check_topic_name(options.right_info_topic, "right_info_topic");
  return options;
}

OwnedCameraInfo::OwnedCameraInfo(const CameraInfo& source)
    : distortion_model(source.distortion_model != nullptr ? source.distortion_model : ""),
      d(source.d._buffer, source.d._buffer + source.d._length),
      info(source) {
  info.header.frame_id = nullptr;  // not kept
  info.distortion_model = runtime::borrow(distortion_model);
  runtime::borrow(info.d, d);
}

bool OwnedCameraInfo::same_calibration(const CameraInfo& other) const {
  const std::string other_model = other.distortion_model != nullptr ? other.distortion_model : "";
  return info.width == other.width && info.height == other.height && distortion_model == other_model &&
         d == std::vector<double>(other.d._buffer, other.d._buffer + other.d._length) &&
         std::memcmp(info.k, other.k, sizeof info.k) == 0 && std::memcmp(info.r, other.r, sizeof info.r) == 0 &&
         std::memcmp(info.p, other.p, sizeof info.p) == 0 && info.binning_x == other.binning_x &&
         info.binning_y == other.binning_y;
}

Ros2Input::Ros2Input(const runtime::CommonArgs& args) : Component("ros2_input", args) {}

std::string Ros2Input::help_notes() {
  const InputOptions defaults;
  return "\nTopics (ROS 2 -> heslam, in the --namespace; docs/ros2.md, ROS 2 input):\n"
         "  rt/LEFT_IMAGE, rt/RIGHT_IMAGE  sensor_msgs/Image mono8|bgr8|rgb8  -> camera/stereo (paired by stamp)\n"
         "  rt/LEFT_INFO, rt/RIGHT_INFO    sensor_msgs/CameraInfo             -> camera/calibration\n"
         "  QoS: sensor data (best effort, volatile, keep last 5)\n"
         "Config fields (--config FILE, all optional):\n"
         "  left_image_topic   (default " +
         defaults.left_image_topic + ")\n  right_image_topic  (default " + defaults.right_image_topic +
         ")\n  left_info_topic    (default " + defaults.left_info_topic + ")\n  right_info_topic   (default " +
         defaults.right_info_topic +
         ")\n"
         "  images             raw (rectified by heslam from K D R P) or rectified (P is their camera; default raw)\n"
         "  end_after_idle_s   end once no image came for this long, s (default 0: run until stopped)\n";
}

void Ros2Input::configure(const runtime::Config& config) {
  options_ = InputOptions::from(config);
  const std::string* image_topics[2] = {&options_.left_image_topic, &options_.right_image_topic};
  const std::string* info_topics[2] = {&options_.left_info_topic, &options_.right_info_topic};
  for (int side = 0; side < 2; ++side) {
    image_readers_[side].emplace(participant(), &sensor_msgs_msg_dds__Image__desc, ros2_topic(*image_topics[side]),
                                 sensor_data_qos());
    info_readers_[side].emplace(participant(), &sensor_msgs_msg_dds__CameraInfo__desc, ros2_topic(*info_topics[side]),
                                sensor_data_qos());
  }
  calibration_writer_.emplace(participant(), topics().calibration());
  frame_writer_.emplace(image_participant().get(), topics().stereo());
  log().info("ROS 2 input: rt/", options_.left_image_topic, " + rt/", options_.right_image_topic, " (",
             options_.images_rectified ? "rectified" : "raw", "), rt/", options_.left_info_topic, " + rt/",
             options_.right_info_topic, " -> ", topics().stereo().name, ", ", topics().calibration().name);
}

void Ros2Input::take_camera_info(StereoPairer::Side side, const CameraInfo& info) {
  const int s = static_cast<int>(side);
  if (infos_[s] && infos_[s]->same_calibration(info)) return;  // drivers repeat it with every image
  infos_[s].emplace(info);
  stats().count("camera_infos");
  if (!infos_[0] || !infos_[1]) return;
  const CameraInfoSource left{infos_[0]->info, info_readers_[0]->name()};
  const CameraInfoSource right{infos_[1]->info, info_readers_[1]->name()};
  try {
    StereoCalibration calibration = to_stereo_calibration(left, right, options_.images_rectified);
    const StereoRectifier rectifier(calibration);
    calibration_writer_->write(CalibrationMessage(calibration, rectifier.camera()).get());
    log().info("calibration from ", calibration.source, ": ", calibration.left.width_px, "x",
               calibration.left.height_px, ", rectified fx ", rectifier.camera().fx_px, " px, baseline ",
               rectifier.camera().baseline_m, " m");
    calibration_ = std::move(calibration);
    stats().count("calibrations_published");
  } catch (const std::exception& error) {
    calibration_.reset();  // images wait for a good one
    stats().count("bad_camera_infos");
    log().warn_throttled("bad_camera_infos", error.what());
  }
}

void Ros2Input::take_image(StereoPairer::Side side, const Image& image) {
  const std::string& topic = image_readers_[static_cast<int>(side)]->name();
  if (!calibration_) {
    stats().count("images_before_calibration");
    log().warn_throttled("images_before_calibration", "topic '", topic,
                         "': image before a usable CameraInfo pair: dropped");
    return;
  }
  try {
    PackedImage packed = to_packed_image(image, topic, static_cast<std::uint32_t>(calibration_->left.width_px),
                                         static_cast<std::uint32_t>(calibration_->left.height_px));
    const std::optional<StereoPairer::Pair> pair =
        pairer_.add(side, to_stamp_ns(image.header.stamp), std::move(packed));
    if (pair) publish(*pair);
  } catch (const std::exception& error) {
    stats().count("bad_images");
    log().warn_throttled("bad_images", error.what());
  }
  if (pairer_.unpaired() > unpaired_reported_) {
    stats().count("unpaired_images", pairer_.unpaired() - unpaired_reported_);
    log().warn_throttled("unpaired_images", pairer_.unpaired(), " images had no partner of the same stamp (",
                         side_name(side), " side last): dropped");
    unpaired_reported_ = pairer_.unpaired();
  }
}

void Ros2Input::publish(const StereoPairer::Pair& pair) {
  if (pair.left.encoding != pair.right.encoding) {
    throw std::runtime_error("topics '" + options_.left_image_topic + "' and '" + options_.right_image_topic +
                             "': field encoding: the pair at stamp " + std::to_string(pair.stamp_ns) +
                             " ns mixes mono8 and colour");
  }
  msg::StereoFrame frame{};
  frame.stamp_ns = pair.stamp_ns;
  frame.stamp_right_ns = pair.stamp_ns;
  frame.seq = next_seq_++;
  frame.width_px = pair.left.width_px;
  frame.height_px = pair.left.height_px;
  frame.encoding = pair.left.encoding;
  runtime::borrow(frame.left, std::span<const std::uint8_t>(pair.left.pixels));
  runtime::borrow(frame.right, std::span<const std::uint8_t>(pair.right.pixels));
  frame_writer_->write(frame);
  stats().count(runtime::kFramesPublished);
}

void Ros2Input::run() {
  while (spin_once(kPollPeriod)) {
    for (int side = 0; side < 2; ++side) {
      const auto s = static_cast<StereoPairer::Side>(side);
      info_readers_[side]->take_all([&](const CameraInfo& info) { take_camera_info(s, info); });
    }
    for (int side = 0; side < 2; ++side) {
      const auto s = static_cast<StereoPairer::Side>(side);
      if (image_readers_[side]->take_all([&](const Image& image) { take_image(s, image); }) > 0) {
        last_image_ = std::chrono::steady_clock::now();
      }
    }
    if (options_.end_after_idle_s > 0.0 && next_seq_ > 0 &&
        std::chrono::steady_clock::now() - last_image_ > std::chrono::duration<double>(options_.end_after_idle_s)) {
      log().info("no image for ", options_.end_after_idle_s, " s: the camera's stream ended");
      break;
    }
  }
  log().info("published ", next_seq_, " stereo frames; ", pairer_.unpaired(), " images unpaired");
}

}  // namespace heslam::ros2

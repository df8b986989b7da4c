// heslam-ros2-input: ROS 2 camera topics in, heslam camera topics out (see ros2_input.hpp).
#include "tools/ros2_bridge/ros2_input.hpp"

#include <algorithm>
#include <cstring>
#include <span>
#include <stdexcept>

#include "components/core/camera/stereo_rectifier.hpp"
#include "components/messages/imu.hpp"
#include "runtime/flags.hpp"
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
// IMU readers: best effort (matches a sensor-data and a reliable driver alike), deep enough for a
// 200 Hz IMU over a second of a stalled poll loop. The frames that wait for the IMU: at most this many.
constexpr int kImuDepth = 200;
constexpr std::size_t kMaxHeldFrames = 20;
// Images held while the CameraInfo pair is not yet usable (both sides together: a second of a 5 Hz pair).
constexpr std::size_t kEarlyImagesHeld = 10;
constexpr double kMaxImuWait_s = 10.0;

const char* side_name(StereoPairer::Side side) { return side == StereoPairer::Side::kLeft ? "left" : "right"; }

void check_topic_name(const std::string& name, const char* field) {
  if (name.empty() || name.front() == '/' || name.back() == '/') {
    throw std::runtime_error(std::string(field) + ": '" + name +
                             "': expected a ROS 2 topic name without leading or trailing '/' (e.g. "
                             "stereo/left/image_raw)");
  }
}

}  // namespace

InputOptions InputOptions::from(const runtime::Config& config, const std::vector<std::string>& flags) {
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
  options.imu_wait_s = config.get_double("imu_wait_s", options.imu_wait_s, 0.0, kMaxImuWait_s);
  options.outage_after_s = config.get_double("outage_after_s", options.outage_after_s, 0.0, kMaxIdle_s);
  runtime::Flags parser("heslam-ros2-input [options]");
  parser.text("--imu-topic", "NAME", &options.imu_topic, "sensor_msgs/Imu topic (empty: no IMU)")
      .path("--imu-calibration", "FILE", &options.imu_calibration, "IMU sensor.yaml (EuRoC) or imu.yaml (Kalibr)")
      .path("--imu-extrinsic", "FILE", &options.imu_extrinsic, "Kalibr camchain or the left camera's sensor.yaml");
  parser.parse(flags);
  if (!options.imu_topic.empty()) {
    check_topic_name(options.imu_topic, "--imu-topic");
    if (options.imu_calibration.empty() || options.imu_extrinsic.empty()) {
      throw std::runtime_error("--imu-topic " + options.imu_topic +
                               ": needs --imu-calibration FILE (the noise model) and --imu-extrinsic FILE (camera "
                               "<- IMU), which sensor_msgs/Imu does not carry (docs/ros2.md)");
    }
  } else if (!options.imu_calibration.empty() || !options.imu_extrinsic.empty()) {
    throw std::runtime_error("--imu-calibration / --imu-extrinsic: given without --imu-topic");
  }
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
         "  end_after_idle_s   end once no image came for this long, s (default 0: run until stopped)\n"
         "  imu_wait_s         the most a frame waits for the IMU to cover its stamp, s (default 0.5)\n"
         "  outage_after_s     no image for this long mid-run: a camera outage, said and counted (default 1; 0: off)\n"
         "IMU (flags, all three or none):\n"
         "  --imu-topic NAME         rt/NAME sensor_msgs/Imu -> imu/readings (best effort, keep last 200)\n"
         "  --imu-calibration FILE   the noise model and rate: EuRoC imu0/sensor.yaml or Kalibr imu.yaml\n"
         "  --imu-extrinsic FILE     camera <- IMU: Kalibr camchain (cam0.T_cam_imu, timeshift_cam_imu) or\n"
         "                           the left camera's EuRoC sensor.yaml (T_BS) -> imu/calibration\n";
}

void Ros2Input::configure(const runtime::Config& config) {
  options_ = InputOptions::from(config, args().rest);
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
  if (!options_.imu_topic.empty()) {
    imu_calibration_ = load_ros2_imu_calibration(options_.imu_calibration, options_.imu_extrinsic);
    imu_reader_.emplace(participant(), &sensor_msgs_msg_dds__Imu__desc, ros2_topic(options_.imu_topic),
                        runtime::Qos(runtime::QosRole::kImu).best_effort().keep_last(kImuDepth).volatile_durability());
    imu_writer_.emplace(participant(), topics().imu());
    imu_calibration_writer_.emplace(participant(), topics().imu_calibration());
    imu_calibration_writer_->write(messages::ImuCalibrationMessage(*imu_calibration_).get());
    const Eigen::Vector3d t = imu_calibration_->T_BS.translation();
    log().info("IMU: rt/", options_.imu_topic, " -> ", topics().imu().name, "; calibration from ",
               imu_calibration_->source, ": ", imu_calibration_->rate_hz, " Hz, IMU at (", t.x(), ", ", t.y(), ", ",
               t.z(), ") m in the left camera, time offset ", imu_calibration_->time_offset_ns, " ns");
  }
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
    std::deque<EarlyImage> early = std::move(early_images_);
    early_images_.clear();
    for (EarlyImage& image : early) pair_image(image.side, image.stamp_ns, std::move(image.packed));
  } catch (const std::exception& error) {
    calibration_.reset();  // images wait for a good one
    stats().count("bad_camera_infos");
    log().warn_throttled("bad_camera_infos", error.what());
  }
}

void Ros2Input::drop_early_images(std::size_t keep) {
  while (early_images_.size() > keep) {
    const int side = static_cast<int>(early_images_.front().side);
    early_images_.pop_front();
    stats().count("images_before_calibration");
    ++images_before_calibration_;
    log().warn_throttled("images_before_calibration", "topic '", image_readers_[side]->name(),
                         "': image before a usable CameraInfo pair: dropped");
  }
}

void Ros2Input::take_image(StereoPairer::Side side, const Image& image) {
  const std::string& topic = image_readers_[static_cast<int>(side)]->name();
  try {
    count_frames_never_received(topic, to_stamp_ns(image.header.stamp));
    // Without a calibration the size cannot be checked yet (0 x 0: any); pair_image checks it.
    PackedImage packed = to_packed_image(image, topic, 0, 0);
    if (!calibration_) {
      early_images_.push_back({side, to_stamp_ns(image.header.stamp), std::move(packed)});
      drop_early_images(kEarlyImagesHeld);
      return;
    }
    pair_image(side, to_stamp_ns(image.header.stamp), std::move(packed));
  } catch (const std::exception& error) {
    stats().count("bad_images");
    ++bad_images_;
    log().warn_throttled("bad_images", error.what());
  }
}

void Ros2Input::count_frames_never_received(const std::string& topic, std::int64_t stamp_ns) {
  const std::uint64_t missing = gaps_.add(stamp_ns);
  if (missing == 0) return;
  stats().count("frames_never_received", missing);
  log().warn_throttled("frames_never_received", "topic '", topic, "': no image of ", missing, " frame(s) before stamp ",
                       stamp_ns, " ns (the camera's period ", static_cast<double>(gaps_.period_ns()) * 1e-6,
                       " ms): lost before the input (its readers' history overrun on a busy machine, the network, "
                       "or the driver); counted as frames_never_received");
}

void Ros2Input::pair_image(StereoPairer::Side side, std::int64_t stamp_ns, PackedImage packed) {
  const std::string& topic = image_readers_[static_cast<int>(side)]->name();
  try {
    const auto width = static_cast<std::uint32_t>(calibration_->left.width_px);
    const auto height = static_cast<std::uint32_t>(calibration_->left.height_px);
    if (packed.width_px != width || packed.height_px != height) {
      throw std::runtime_error("topic '" + topic + "': field width/height: " + std::to_string(packed.width_px) + "x" +
                               std::to_string(packed.height_px) + " differs from the CameraInfo's " +
                               std::to_string(width) + "x" + std::to_string(height));
    }
    std::optional<StereoPairer::Pair> pair = pairer_.add(side, stamp_ns, std::move(packed));
    if (pair) {
      check_same_encoding(*pair, image_readers_[0]->name(), image_readers_[1]->name());
      held_.push_back({std::move(*pair), std::chrono::steady_clock::now()});
    }
  } catch (const std::exception& error) {
    stats().count("bad_images");
    ++bad_images_;
    log().warn_throttled("bad_images", error.what());
  }
  if (pairer_.unpaired() > unpaired_reported_) {
    stats().count("unpaired_images", pairer_.unpaired() - unpaired_reported_);
    log().warn_throttled("unpaired_images", pairer_.unpaired(), " images had no partner of the same stamp (",
                         side_name(side), " side last): dropped");
    unpaired_reported_ = pairer_.unpaired();
  }
}

void Ros2Input::take_imu(const Imu& imu) {
  const std::string& topic = imu_reader_->name();
  try {
    imu_.add(to_imu_sample(imu, topic));
    stats().count("imu_readings");
  } catch (const UnusableImu&) {
    throw;  // the sensor cannot serve: the run ends with its line
  } catch (const std::exception& error) {
    stats().count("bad_imu_readings");
    ++bad_imu_readings_;
    log().warn_throttled("bad_imu_readings", "topic '", topic, "': ", error.what());
  }
}

void Ros2Input::publish_imu(const ImuForwarder::Batch& batch, bool end_of_stream) {
  const messages::ImuBatchMessage message(batch.samples, imu_seq_++, batch.first_index, batch.watermark_ns,
                                          end_of_stream);
  imu_writer_->write(message.get());
  stats().count("imu_readings_published", batch.samples.size());
}

void Ros2Input::release_frames(bool flush) {
  const auto now = std::chrono::steady_clock::now();
  const auto wait = std::chrono::duration<double>(options_.imu_wait_s);
  while (!held_.empty()) {
    HeldFrame& held = held_.front();
    if (imu_reader_) {
      // The frame's stamp on the IMU's clock (t_imu = t_camera + time_offset_ns).
      const std::int64_t imu_stamp_ns = held.pair.stamp_ns + imu_calibration_->time_offset_ns;
      if (imu_.watermark_ns() < imu_stamp_ns) {
        if (!flush && now - held.since < wait && held_.size() <= kMaxHeldFrames) break;
        publish_imu(imu_.silent_until(imu_stamp_ns));
        stats().count("frames_without_imu");
        ++frames_without_imu_;
        log().warn_throttled("frames_without_imu", "topic 'rt/", options_.imu_topic, "': no reading at or after frame ",
                             held.pair.stamp_ns, " ns within ", options_.imu_wait_s,
                             " s: the frame goes out with the IMU declared silent up to its stamp");
      }
    }
    publish(held.pair);
    held_.pop_front();
  }
}

void Ros2Input::publish(const StereoPairer::Pair& pair) {
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
    if (imu_reader_) {
      imu_reader_->take_all([&](const Imu& imu) { take_imu(imu); });
      if (const std::optional<ImuForwarder::Batch> batch = imu_.take_batch()) publish_imu(*batch);
    }
    for (int side = 0; side < 2; ++side) {
      const auto s = static_cast<StereoPairer::Side>(side);
      if (const int taken = image_readers_[side]->take_all([&](const Image& image) { take_image(s, image); });
          taken > 0) {
        images_received_ += static_cast<std::uint64_t>(taken);
        const auto now = std::chrono::steady_clock::now();
        if (in_outage_) {
          log().info("images again after ", std::chrono::duration<double>(now - last_image_).count(),
                     " s without any (camera outage ", camera_outages_, ")");
          in_outage_ = false;
        }
        last_image_ = now;
      }
    }
    release_frames(false);
    // A camera that stops mid-run (unplugged, its driver died): said once per outage, counted; the input
    // waits for it (a restarted driver publishes again), or ends with end_after_idle_s.
    if (images_received_ > 0 && !in_outage_ && options_.outage_after_s > 0.0 &&
        std::chrono::steady_clock::now() - last_image_ > std::chrono::duration<double>(options_.outage_after_s)) {
      in_outage_ = true;
      ++camera_outages_;
      stats().count("camera_outages");
      log().warn(
          "no image on rt/", options_.left_image_topic, " or rt/", options_.right_image_topic, " for ",
          options_.outage_after_s, " s after ", images_received_, " images (", next_seq_,
          " frames published): the camera stopped (unplugged, or its driver ended); waiting for it (camera outage ",
          camera_outages_, ")");
    }
    if (options_.end_after_idle_s > 0.0 && images_received_ > 0 &&
        std::chrono::steady_clock::now() - last_image_ > std::chrono::duration<double>(options_.end_after_idle_s)) {
      log().info("no image for ", options_.end_after_idle_s, " s: the camera's stream ended");
      break;
    }
  }
  if (imu_reader_) {
    imu_reader_->take_all([&](const Imu& imu) { take_imu(imu); });
    if (const std::optional<ImuForwarder::Batch> batch = imu_.take_batch()) publish_imu(*batch);
  }
  drop_early_images(0);  // the calibration never came: each counted
  release_frames(true);
  if (imu_reader_) {
    publish_imu(ImuForwarder::Batch{{}, imu_.taken(), imu_.watermark_ns()}, true);
    log().info("IMU: ", imu_.taken(), " readings forwarded, ", bad_imu_readings_, " dropped, ", frames_without_imu_,
               " frames went out without the IMU covering them");
  }
  log().info("published ", next_seq_, " stereo frames; ", pairer_.unpaired(), " images unpaired, ",
             images_before_calibration_, " before a usable CameraInfo pair, ", bad_images_, " bad; ", gaps_.missing(),
             " frames never received (gaps in the stamps); ", camera_outages_, " camera outages");
  if (images_received_ > 0 && next_seq_ == 0) {
    throw std::runtime_error("received " + std::to_string(images_received_) +
                             " images but published no stereo frame (each drop counted and said above)");
  }
}

}  // namespace heslam::ros2

// heslam-test-ros2-camera: plays an EuRoC folder as a ROS 2 stereo camera driver would, with only ROS 2
// wire types and topic names: sensor_msgs/Image (mono8) on rt/stereo/{left,right}/image_raw and
// sensor_msgs/CameraInfo (plumb_bob K D, and R P from cv::stereoRectify as ROS 2's camera_calibration
// writes them) on rt/stereo/{left,right}/camera_info, paced by the stamps in real time (--rate); with
// --imu-topic NAME also the dataset's imu0/ as sensor_msgs/Imu on rt/NAME (an IMU driver's message per
// reading at its stamp's time; orientation not given: orientation_covariance[0] = -1, as REP 145 says).
// With --tf-latency on it also reads rt/tf (heslam-ros2-bridge's map -> odom -> base_link) and prints the
// latency from each left image's publication to the reception of the TF of its stamp: p50 / p99 / max
// over the frames that got one, and how many did not (its TF reader is polled every ms: +-1 ms).
//   heslam-test-ros2-camera --domain N --dataset DIR [--rate R] [--wait-readers-s S] [--imu-topic NAME]
//                           [--tf-latency on] [--pause-after N --pause-s S] [--right-encoding bgr8]
// Bad input on purpose: --pause-after N --pause-s S stops sending for S s after N frames (a camera
// unplugged and plugged again); --right-encoding bgr8 sends the right images in colour (a mono/colour mixup).
// Exit 0 when every frame was sent, 1 with one line on an unusable dataset or no reader.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "runtime/participant.hpp"
#include "runtime/qos.hpp"
#include "runtime/sequence.hpp"
#include "tools/dataset/imu_reader.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/dataset/stereo_images.hpp"
#include "tools/ros2_bridge/ros2_conversions.hpp"
#include "tools/ros2_bridge/ros2_reader.hpp"
#include "tools/ros2_bridge/ros2_writer.hpp"

namespace {

using namespace heslam;
using namespace heslam::ros2;

struct CameraInfoStorage {
  std::string model = "plumb_bob";
  std::string frame_id;
  std::vector<double> d;
  CameraInfo info{};
};

void fill_info(CameraInfoStorage& storage, const CameraModel& camera, const cv::Mat& R, const cv::Mat& P) {
  CameraInfo& info = storage.info;
  info.width = static_cast<std::uint32_t>(camera.width_px);
  info.height = static_cast<std::uint32_t>(camera.height_px);
  storage.d = camera.distortion;
  storage.d.resize(5, 0.0);
  info.distortion_model = runtime::borrow(storage.model);
  runtime::borrow(info.d, storage.d);
  const double k[9] = {camera.fx_px, 0.0, camera.cx_px, 0.0, camera.fy_px, camera.cy_px, 0.0, 0.0, 1.0};
  std::copy(std::begin(k), std::end(k), info.k);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) info.r[3 * r + c] = R.at<double>(r, c);
    for (int c = 0; c < 4; ++c) info.p[4 * r + c] = P.at<double>(r, c);
  }
  info.header.frame_id = runtime::borrow(storage.frame_id);
}

cv::Mat camera_matrix(const CameraModel& c) {
  return (cv::Mat_<double>(3, 3) << c.fx_px, 0.0, c.cx_px, 0.0, c.fy_px, c.cy_px, 0.0, 0.0, 1.0);
}

// Image publication -> TF reception per stamp, read on a thread of its own.
class TfLatency {
 public:
  explicit TfLatency(const runtime::Participant& participant)
      : reader_(participant, &tf2_msgs_msg_dds__TFMessage__desc, ros2_topic("tf"),
                runtime::Qos(runtime::QosRole::kOdometry).keep_last(100).volatile_durability()),
        thread_([this] { poll(); }) {}
  ~TfLatency() {
    stop_ = true;
    thread_.join();
  }
  void sent(std::int64_t stamp_ns) {
    const std::lock_guard lock(mutex_);
    sent_[stamp_ns] = std::chrono::steady_clock::now();
  }
  // p50 / p99 / max of the frames that got a TF, and how many did not.
  void report() {
    const std::lock_guard lock(mutex_);
    std::vector<double> latencies_ms;
    for (const auto& [stamp, at] : sent_) {
      const auto tf = received_.find(stamp);
      if (tf != received_.end())
        latencies_ms.push_back(std::chrono::duration<double, std::milli>(tf->second - at).count());
    }
    std::sort(latencies_ms.begin(), latencies_ms.end());
    const auto rank = [&](double q) {  // nearest rank
      return latencies_ms[std::min(latencies_ms.size() - 1, static_cast<std::size_t>(q * latencies_ms.size()))];
    };
    if (latencies_ms.empty()) {
      std::printf("TF latency: no TF for any of the %zu frames sent\n", sent_.size());
      return;
    }
    std::printf(
        "TF latency (image published -> its TF received): %zu of %zu frames, p50 %.1f ms, p99 %.1f ms, "
        "max %.1f ms; %zu frames without a TF\n",
        latencies_ms.size(), sent_.size(), rank(0.5), rank(0.99), latencies_ms.back(),
        sent_.size() - latencies_ms.size());
  }

 private:
  void poll() {
    while (!stop_) {
      reader_.take_all([&](const TFMessage& message) {
        const auto now = std::chrono::steady_clock::now();
        if (message.transforms._length == 0) return;
        const Time& stamp = message.transforms._buffer[0].header.stamp;
        const std::int64_t stamp_ns = static_cast<std::int64_t>(stamp.sec) * 1'000'000'000 + stamp.nanosec;
        const std::lock_guard lock(mutex_);
        received_.emplace(stamp_ns, now);
      });
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

  Ros2Reader<TFMessage> reader_;
  std::mutex mutex_;
  std::map<std::int64_t, std::chrono::steady_clock::time_point> sent_, received_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

int run(int argc, char** argv) {
  int domain = -1;
  std::string dataset_path;
  double rate = 1.0;
  double wait_readers_s = 30.0;
  std::string imu_topic;
  bool tf_latency = false;
  long pause_after = -1;  // frames
  double pause_s = 0.0;
  std::string right_encoding = "mono8";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--domain") domain = std::atoi(argv[i + 1]);
    if (flag == "--dataset") dataset_path = argv[i + 1];
    if (flag == "--rate") rate = std::atof(argv[i + 1]);
    if (flag == "--wait-readers-s") wait_readers_s = std::atof(argv[i + 1]);
    if (flag == "--imu-topic") imu_topic = argv[i + 1];
    if (flag == "--tf-latency") tf_latency = std::string(argv[i + 1]) == "on";
    if (flag == "--pause-after") pause_after = std::atol(argv[i + 1]);
    if (flag == "--pause-s") pause_s = std::atof(argv[i + 1]);
    if (flag == "--right-encoding") right_encoding = argv[i + 1];
  }
  if (domain < 0 || dataset_path.empty() || !(rate > 0.0)) {
    std::fprintf(stderr,
                 "usage: heslam-test-ros2-camera --domain N --dataset DIR [--rate R] [--wait-readers-s S] "
                 "[--imu-topic NAME] [--tf-latency on] [--pause-after N --pause-s S] [--right-encoding bgr8]\n");
    return 2;
  }
  const StereoDataset dataset = open_dataset(dataset_path);
  const StereoCalibration& calibration = dataset.calibration;
  const cv::Size size(calibration.left.width_px, calibration.left.height_px);
  const Pose3 T_rl = calibration.T_rl();
  cv::Mat R(3, 3, CV_64F), T(3, 1, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R.at<double>(r, c) = T_rl.linear()(r, c);
    T.at<double>(r, 0) = T_rl.translation()(r);
  }
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(camera_matrix(calibration.left), cv::Mat(calibration.left.distortion),
                    camera_matrix(calibration.right), cv::Mat(calibration.right.distortion), size, R, T, R1, R2, P1, P2,
                    Q, cv::CALIB_ZERO_DISPARITY, 0.0, size);
  CameraInfoStorage infos[2];
  infos[0].frame_id = "left_camera_optical_frame";
  infos[1].frame_id = "right_camera_optical_frame";
  fill_info(infos[0], calibration.left, R1, P1);
  fill_info(infos[1], calibration.right, R2, P2);

  runtime::Participant participant({.domain_id = domain, .dds_config = ""});
  // A driver's publisher: reliable, volatile, keep last 5 (a best-effort sensor-data reader matches it).
  const runtime::Qos qos = runtime::Qos(runtime::QosRole::kImages).keep_last(5).volatile_durability();
  const char* sides[2] = {"left", "right"};
  std::optional<Ros2Writer<Image>> images[2];
  std::optional<Ros2Writer<CameraInfo>> info_writers[2];
  for (int side = 0; side < 2; ++side) {
    images[side].emplace(participant, &sensor_msgs_msg_dds__Image__desc,
                         ros2_topic(std::string("stereo/") + sides[side] + "/image_raw"), qos);
    info_writers[side].emplace(participant, &sensor_msgs_msg_dds__CameraInfo__desc,
                               ros2_topic(std::string("stereo/") + sides[side] + "/camera_info"), qos);
  }
  if (!images[0]->wait_for_readers(std::chrono::duration<double>(wait_readers_s)) ||
      !images[1]->wait_for_readers(std::chrono::duration<double>(wait_readers_s))) {
    std::fprintf(stderr, "heslam-test-ros2-camera: no reader of rt/stereo/*/image_raw within %g s\n", wait_readers_s);
    return 1;
  }
  // An IMU driver's publisher: reliable, volatile, keep last 100 (ROS 2's default depth is 10).
  std::optional<ImuRecording> imu;
  std::optional<Ros2Writer<Imu>> imu_writer;
  std::size_t next_reading = 0;
  if (!imu_topic.empty()) {
    imu = read_euroc_imu(dataset_path);
    imu_writer.emplace(participant, &sensor_msgs_msg_dds__Imu__desc, ros2_topic(imu_topic),
                       runtime::Qos(runtime::QosRole::kImu).keep_last(100).volatile_durability());
    if (!imu_writer->wait_for_readers(std::chrono::duration<double>(wait_readers_s))) {
      std::fprintf(stderr, "heslam-test-ros2-camera: no reader of rt/%s within %g s\n", imu_topic.c_str(),
                   wait_readers_s);
      return 1;
    }
    // The readings from the last one at or before the first frame (as the replay starts its IMU).
    while (next_reading + 1 < imu->samples.size() &&
           imu->samples[next_reading + 1].stamp_ns <= dataset.frames.front().stamp_ns) {
      ++next_reading;
    }
  }
  std::optional<TfLatency> latency;
  if (tf_latency) latency.emplace(participant);
  const std::string imu_frame_id = "imu_link";
  auto start = std::chrono::steady_clock::now();
  const std::int64_t first_stamp = dataset.frames.front().stamp_ns;
  const auto at = [&](std::int64_t stamp_ns) {
    return start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                       std::chrono::duration<double>(static_cast<double>(stamp_ns - first_stamp) * 1e-9 / rate));
  };
  std::size_t readings_sent = 0;
  // Every reading up to stamp_ns, each at its time.
  const auto send_imu_until = [&](std::int64_t stamp_ns) {
    for (; imu && next_reading < imu->samples.size() && imu->samples[next_reading].stamp_ns <= stamp_ns;
         ++next_reading) {
      const ImuSample& sample = imu->samples[next_reading];
      std::this_thread::sleep_until(at(sample.stamp_ns));
      Imu message{};
      message.header.stamp = to_time(sample.stamp_ns);
      message.header.frame_id = runtime::borrow(imu_frame_id);
      message.orientation.w = 1.0;
      message.orientation_covariance[0] = -1.0;  // no orientation estimate
      message.angular_velocity = {sample.gyro_rad_s.x(), sample.gyro_rad_s.y(), sample.gyro_rad_s.z()};
      message.linear_acceleration = {sample.accel_m_s2.x(), sample.accel_m_s2.y(), sample.accel_m_s2.z()};
      imu_writer->write(message);
      ++readings_sent;
    }
  };
  long sent = 0;
  for (const StereoFrameFiles& frame : dataset.frames) {
    if (sent++ == pause_after) {
      std::this_thread::sleep_for(std::chrono::duration<double>(pause_s));
      start += std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(pause_s));
    }
    const StereoImages pair = load_stereo_images(frame, size);
    if (pair.encoding != "mono8") throw std::runtime_error(frame.left.string() + ": expected grey (mono8) images");
    send_imu_until(frame.stamp_ns);
    std::this_thread::sleep_until(at(frame.stamp_ns));
    cv::Mat right_colour;
    if (right_encoding == "bgr8") cv::cvtColor(pair.right, right_colour, cv::COLOR_GRAY2BGR);
    const cv::Mat* mats[2] = {&pair.left, right_colour.empty() ? &pair.right : &right_colour};
    for (int side = 0; side < 2; ++side) {
      infos[side].info.header.stamp = to_time(frame.stamp_ns);
      info_writers[side]->write(infos[side].info);
      const std::string encoding = side == 1 ? right_encoding : "mono8";
      Image image{};
      image.header.stamp = to_time(frame.stamp_ns);  // both images of a pair stamped alike, as drivers do
      image.header.frame_id = runtime::borrow(infos[side].frame_id);
      image.width = static_cast<std::uint32_t>(mats[side]->cols);
      image.height = static_cast<std::uint32_t>(mats[side]->rows);
      image.encoding = runtime::borrow(encoding);
      image.step = static_cast<std::uint32_t>(mats[side]->step[0]);
      runtime::borrow(image.data,
                      std::span<const std::uint8_t>(mats[side]->data, mats[side]->total() * mats[side]->elemSize()));
      images[side]->write(image);
      if (side == 0 && latency) latency->sent(frame.stamp_ns);
    }
  }
  // The readings that cover the last frame (the first one after it).
  if (imu && next_reading < imu->samples.size()) send_imu_until(imu->samples[next_reading].stamp_ns);
  std::printf("sent %zu stereo frames, %zu IMU readings\n", dataset.frames.size(), readings_sent);
  if (latency) {
    std::this_thread::sleep_for(std::chrono::seconds(2));  // the last frames' TF
    latency->report();
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "heslam-test-ros2-camera: %s\n", error.what());
    return 1;
  }
}

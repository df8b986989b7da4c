// heslam-test-ros2-camera: plays an EuRoC folder as a ROS 2 stereo camera driver would, with only ROS 2
// wire types and topic names: sensor_msgs/Image (mono8) on rt/stereo/{left,right}/image_raw and
// sensor_msgs/CameraInfo (plumb_bob K D, and R P from cv::stereoRectify as ROS 2's camera_calibration
// writes them) on rt/stereo/{left,right}/camera_info, paced by the stamps in real time (--rate).
//   heslam-test-ros2-camera --domain N --dataset DIR [--rate R] [--wait-readers-s S]
// Exit 0 when every frame was sent, 1 with one line on an unusable dataset or no reader.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "runtime/participant.hpp"
#include "runtime/qos.hpp"
#include "runtime/sequence.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/dataset/stereo_images.hpp"
#include "tools/ros2_bridge/ros2_conversions.hpp"
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

int run(int argc, char** argv) {
  int domain = -1;
  std::string dataset_path;
  double rate = 1.0;
  double wait_readers_s = 30.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--domain") domain = std::atoi(argv[i + 1]);
    if (flag == "--dataset") dataset_path = argv[i + 1];
    if (flag == "--rate") rate = std::atof(argv[i + 1]);
    if (flag == "--wait-readers-s") wait_readers_s = std::atof(argv[i + 1]);
  }
  if (domain < 0 || dataset_path.empty() || !(rate > 0.0)) {
    std::fprintf(stderr, "usage: heslam-test-ros2-camera --domain N --dataset DIR [--rate R] [--wait-readers-s S]\n");
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
  const auto start = std::chrono::steady_clock::now();
  const std::int64_t first_stamp = dataset.frames.front().stamp_ns;
  for (const StereoFrameFiles& frame : dataset.frames) {
    const StereoImages pair = load_stereo_images(frame, size);
    if (pair.encoding != "mono8") throw std::runtime_error(frame.left.string() + ": expected grey (mono8) images");
    std::this_thread::sleep_until(
        start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                    std::chrono::duration<double>(static_cast<double>(frame.stamp_ns - first_stamp) * 1e-9 / rate)));
    const cv::Mat* mats[2] = {&pair.left, &pair.right};
    for (int side = 0; side < 2; ++side) {
      infos[side].info.header.stamp = to_time(frame.stamp_ns);
      info_writers[side]->write(infos[side].info);
      const std::string encoding = "mono8";
      Image image{};
      image.header.stamp = to_time(frame.stamp_ns);  // both images of a pair stamped alike, as drivers do
      image.header.frame_id = runtime::borrow(infos[side].frame_id);
      image.width = static_cast<std::uint32_t>(mats[side]->cols);
      image.height = static_cast<std::uint32_t>(mats[side]->rows);
      image.encoding = runtime::borrow(encoding);
      image.step = image.width;
      runtime::borrow(image.data,
                      std::span<const std::uint8_t>(mats[side]->data, mats[side]->total() * mats[side]->elemSize()));
      images[side]->write(image);
    }
  }
  std::printf("sent %zu stereo frames\n", dataset.frames.size());
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

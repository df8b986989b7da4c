// heslam-ros2-input: a ROS 2 stereo camera as heslam's camera source. It reads a ROS 2 camera driver's
// topics with ROS 2's wire types, without ROS code (docs/ros2.md, ROS 2 input):
//
//   rt/<left_image_topic>,  rt/<right_image_topic>   sensor_msgs/Image (mono8, bgr8, rgb8)
//   rt/<left_info_topic>,   rt/<right_info_topic>    sensor_msgs/CameraInfo (plumb_bob, rational_polynomial)
//     QoS as ROS 2's sensor data profile (best effort, volatile, keep last 5), which camera drivers use
//
//   rt/<imu_topic>                                    sensor_msgs/Imu (with --imu-topic; best effort, keep last 200)
//
// and publishes what heslam-replay publishes: camera/calibration (from the two CameraInfo, once they
// arrived, again when they change) and camera/stereo (left and right paired by stamp, seq 0, 1, ...);
// with an IMU, imu/readings (a batch per poll, watermark its last stamp) and imu/calibration (from the
// files of --imu-calibration and --imu-extrinsic, as sensor_msgs/Imu carries neither), and a frame goes
// out only once the IMU's watermark reached its stamp (the ordering contract of docs/topics.md), or
// after imu_wait_s without it (counted: the IMU is then declared silent up to the frame's stamp).
// Real time only: a camera is never lockstep. Bad input (an encoding it does not take, a size that
// disagrees with the CameraInfo, a mono/colour pair, stamps going backwards, an unpaired image, a camera
// that stops mid-run, a bad IMU reading) is one line and a count; an orientation-only IMU, or images
// received but no frame published, end the input with exit 1 and one line.
//
// Config fields (all optional): left_image_topic ("stereo/left/image_raw"), right_image_topic
// ("stereo/right/image_raw"), left_info_topic ("stereo/left/camera_info"), right_info_topic
// ("stereo/right/camera_info"), images ("raw": rectified by heslam from K D R P; "rectified": already
// rectified, P is their camera), end_after_idle_s (0: run until stopped), imu_wait_s (0.5),
// outage_after_s (1).
// Flags: --imu-topic NAME, --imu-calibration FILE, --imu-extrinsic FILE (all three or none).
#pragma once

#include <chrono>
#include <deque>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "components/core/camera/stereo_calibration.hpp"
#include "runtime/component.hpp"
#include "runtime/writer.hpp"
#include "tools/ros2_bridge/ros2_input_conversions.hpp"
#include "tools/ros2_bridge/ros2_reader.hpp"

namespace heslam::ros2 {

struct InputOptions {
  std::string left_image_topic = "stereo/left/image_raw";
  std::string right_image_topic = "stereo/right/image_raw";
  std::string left_info_topic = "stereo/left/camera_info";
  std::string right_info_topic = "stereo/right/camera_info";
  bool images_rectified = false;
  // > 0: end (exit 0) once frames were published and no image came for this long, as a replay ends
  // with its recording (a pipeline's run then ends); 0: run until stopped (a live camera).
  double end_after_idle_s = 0.0;
  // IMU (flags; empty topic: no IMU): the ROS 2 topic and the files of the calibration it lacks
  // (load_ros2_imu_calibration); a frame waits at most imu_wait_s for the IMU to cover its stamp.
  std::string imu_topic;
  std::filesystem::path imu_calibration;
  std::filesystem::path imu_extrinsic;
  double imu_wait_s = 0.5;
  // No image for this long after frames went out: a camera outage, one line and counted (0: not watched).
  double outage_after_s = 1.0;

  // Throws std::runtime_error naming the field or flag on a bad value.
  static InputOptions from(const runtime::Config& config, const std::vector<std::string>& flags = {});
};

// A CameraInfo that owns its strings and sequences (a taken sample's die with the take).
struct OwnedCameraInfo {
  explicit OwnedCameraInfo(const CameraInfo& info);
  OwnedCameraInfo(const OwnedCameraInfo&) = delete;
  OwnedCameraInfo& operator=(const OwnedCameraInfo&) = delete;
  bool same_calibration(const CameraInfo& other) const;

  std::string distortion_model;
  std::vector<double> d;
  CameraInfo info{};
};

class Ros2Input : public runtime::Component {
 public:
  explicit Ros2Input(const runtime::CommonArgs& args);

  static std::string help_notes();

 private:
  bool accepts_positional_args() const override { return true; }  // --imu-topic NAME, ... (InputOptions::from)
  void configure(const runtime::Config& config) override;
  void run() override;

  void take_camera_info(StereoPairer::Side side, const CameraInfo& info);
  void take_image(StereoPairer::Side side, const Image& image);
  void publish(const StereoPairer::Pair& pair);
  void take_imu(const Imu& imu);
  void publish_imu(const ImuForwarder::Batch& batch, bool end_of_stream = false);
  // Publishes the held frames the IMU covers (all of them without an IMU); with flush, all of them, and in any
  // case those held longer than imu_wait_s (after declaring the IMU silent up to their stamps).
  void release_frames(bool flush);

  InputOptions options_;
  std::optional<Ros2Reader<Image>> image_readers_[2];
  std::optional<Ros2Reader<CameraInfo>> info_readers_[2];
  std::optional<runtime::Writer<msg::StereoCalibration>> calibration_writer_;
  std::optional<runtime::Writer<msg::StereoFrame>> frame_writer_;
  std::optional<OwnedCameraInfo> infos_[2];
  std::optional<StereoCalibration> calibration_;  // published; images are checked against its size
  // Images that came before a usable CameraInfo pair (a driver publishes both at once, and the two
  // CameraInfos may arrive a poll apart): held, a few per side, until the calibration is there.
  struct EarlyImage {
    StereoPairer::Side side;
    std::int64_t stamp_ns;
    PackedImage packed;
  };
  std::deque<EarlyImage> early_images_;
  // The image into the pairer (and a pair to the frames held for the IMU), checked against the
  // calibration's size; a bad one counted and said.
  void pair_image(StereoPairer::Side side, std::int64_t stamp_ns, PackedImage packed);
  // Frames of which no image of either side arrived, found by this image's stamp: counted, said.
  void count_frames_never_received(const std::string& topic, std::int64_t stamp_ns);
  // Drops early images beyond `keep`, counting each as an image before a usable CameraInfo pair.
  void drop_early_images(std::size_t keep);
  StereoPairer pairer_;
  FrameGapCounter gaps_;  // frames of which no image arrived
  std::uint64_t next_seq_ = 0;
  std::uint64_t unpaired_reported_ = 0;
  std::uint64_t images_before_calibration_ = 0;
  std::uint64_t bad_images_ = 0;
  std::uint64_t camera_outages_ = 0;
  std::uint64_t images_received_ = 0;
  bool in_outage_ = false;
  std::chrono::steady_clock::time_point last_image_;
  // IMU
  std::optional<Ros2Reader<Imu>> imu_reader_;
  std::optional<runtime::Writer<msg::ImuBatch>> imu_writer_;
  std::optional<runtime::Writer<msg::ImuCalibration>> imu_calibration_writer_;
  std::optional<ImuCalibration> imu_calibration_;
  ImuForwarder imu_;
  std::uint64_t imu_seq_ = 0;
  std::uint64_t bad_imu_readings_ = 0;
  std::uint64_t frames_without_imu_ = 0;
  struct HeldFrame {
    StereoPairer::Pair pair;
    std::chrono::steady_clock::time_point since;
  };
  std::deque<HeldFrame> held_;  // paired frames waiting for the IMU's watermark
};

}  // namespace heslam::ros2

// ROS 2 camera topics -> heslam's camera input, DDS-free so they are unit-tested on known values (the
// conversions of a ROS 2 stereo input; docs/ros2.md, ROS 2 input):
// - two sensor_msgs/CameraInfo (left, right) -> heslam's StereoCalibration. ROS 2's CameraInfo always
//   describes the raw camera: K, D (plumb_bob k1 k2 p1 p2 k3, or rational_polynomial k1..k6 p1 p2
//   whose k4..k6 are 0), the rectifying rotation R and the rectified projection P (the right one's
//   P[0][3] = -fx * baseline). For raw images this becomes an explicit rectification (as ORB-SLAM2's
//   LEFT.K/D/R/P); for images already rectified (image_proc's image_rect) the rectified pinhole P.
// - sensor_msgs/Image mono8 / bgr8 / rgb8 -> packed MONO8 or BGR8 pixels (rgb8 reordered), refusing
//   every other encoding, a step or data size that disagrees, or a size that is not the CameraInfo's.
// - sensor_msgs/Imu -> an ImuSample (angular_velocity, linear_acceleration in the IMU's frame), and the
//   IMU calibration sensor_msgs/Imu does not carry (noise model, rate, camera <- IMU extrinsic, time
//   offset) from the files a user has: an IMU sensor.yaml (EuRoC) or imu.yaml (Kalibr) plus a Kalibr
//   camchain (cam0.T_cam_imu, timeshift_cam_imu) or the left camera's EuRoC sensor.yaml (T_BS).
// Every refusal is a std::runtime_error whose what() is one line naming the topic and the field.
#pragma once

#include <climits>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/imu/imu_buffer.hpp"
#include "runtime/messages.hpp"
#include "tools/ros2_bridge/ros2_messages.hpp"

namespace heslam::ros2 {

struct CameraInfoSource {
  const CameraInfo& info;
  const std::string& topic;  // for the messages
};

StereoCalibration to_stereo_calibration(const CameraInfoSource& left, const CameraInfoSource& right,
                                        bool images_rectified);

struct PackedImage {
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  heslam_msg_ImageEncoding encoding = heslam_msg_ENCODING_MONO8;
  std::vector<std::uint8_t> pixels;  // width x height x channels, no row padding
};

// `expected_width_px` / `expected_height_px`: the CameraInfo's (0: not checked).
PackedImage to_packed_image(const Image& image, const std::string& topic, std::uint32_t expected_width_px,
                            std::uint32_t expected_height_px);

// The stamp of a ROS 2 header in ns.
std::int64_t to_stamp_ns(const Time& time);

// Pairs left and right images by their header stamp (a ROS 2 stereo driver stamps both images of a pair
// alike). An image whose partner has not come waits, at most kMaxPending per side; when a pair is made,
// the older waiting images of both sides can no longer pair and are dropped and counted (unpaired()).
class StereoPairer {
 public:
  enum class Side { kLeft = 0, kRight = 1 };
  struct Pair {
    std::int64_t stamp_ns = 0;
    PackedImage left;
    PackedImage right;
  };
  static constexpr std::size_t kMaxPending = 5;  // the sensor-data QoS depth of the readers

  // The pair this image completes, if any. Throws std::runtime_error (nothing changed) for a stamp not
  // after the last pair's (stamps going backwards, or an image that came too late to pair).
  std::optional<Pair> add(Side side, std::int64_t stamp_ns, PackedImage image);
  std::uint64_t unpaired() const { return unpaired_; }
  std::optional<std::int64_t> last_pair_stamp_ns() const { return last_pair_stamp_ns_; }

 private:
  std::map<std::int64_t, PackedImage> pending_[2];
  std::optional<std::int64_t> last_pair_stamp_ns_;
  std::uint64_t unpaired_ = 0;
};

// Frames of which no image of either side ever arrived (a best-effort reader's KEEP_LAST overrun on a busy
// machine, the network, the driver): no count of them can come from DDS, so they are read from the gaps
// in the image stamps, against the median of the last kIntervals ordinary intervals (a camera's period,
// its jitter well under half of it). Fed every image's stamp, of either side and in arrival order (a stamp
// not after the newest fed is ignored: the other side's image of a frame, or one out of order). The
// first kJudgeAfter intervals are judged once there are that many; frames lost before the first image
// or after the last one cannot be seen.
class FrameGapCounter {
 public:
  static constexpr std::size_t kIntervals = 15;
  static constexpr std::size_t kJudgeAfter = 3;
  static constexpr double kGapFactor = 1.5;  // an interval over 1.5 periods misses frames

  // The frames found missing with this stamp (those before it, or the first intervals' once judged).
  std::uint64_t add(std::int64_t stamp_ns);
  std::uint64_t missing() const { return missing_; }
  // The camera's period as judged so far (0 before kJudgeAfter intervals).
  std::int64_t period_ns() const;

 private:
  std::uint64_t judge(std::int64_t interval_ns);  // the frames missing in it; keeps an ordinary one

  std::optional<std::int64_t> newest_ns_;
  std::vector<std::int64_t> intervals_;  // the last kIntervals ordinary ones, oldest first
  bool judging_ = false;
  std::uint64_t missing_ = 0;
};

// Throws std::runtime_error naming both topics when the pair mixes mono8 and colour (a left and a right
// driver configured differently).
void check_same_encoding(const StereoPairer::Pair& pair, const std::string& left_topic, const std::string& right_topic);

// An IMU that gives no linear acceleration or no angular velocity (covariance[0] == -1, REP 145): an
// orientation-only IMU, which heslam's inertial tracking cannot use. Not a bad reading: a wrong sensor.
struct UnusableImu : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The reading of one sensor_msgs/Imu. Throws UnusableImu for an orientation-only IMU, std::runtime_error
// naming the topic and the field for a non-finite value or a negative stamp.
ImuSample to_imu_sample(const Imu& imu, const std::string& topic);

// The IMU's calibration for imu/calibration, in the frame of heslam-ros2-input's body (the left camera,
// whose T_BS is the identity): T_BS = T_cam_imu.
//   imu_file: an EuRoC imu0/sensor.yaml (rate_hz, T_BS: IMU -> EuRoC body) or a Kalibr imu.yaml
//     (update_rate; no T_BS: the IMU is its own frame), with the four noise figures (*_noise_density,
//     *_random_walk) of either.
//   extrinsic_file: a Kalibr camchain (cam0.T_cam_imu; timeshift_cam_imu in s, t_imu = t_cam + shift,
//     optional) -> T_BS = cam0.T_cam_imu; or the left camera's EuRoC sensor.yaml (T_BS: cam0 -> EuRoC
//     body) -> T_BS = T_BS(cam0)^-1 T_BS(imu), time offset 0.
// Throws std::runtime_error with one line naming the file and the field.
ImuCalibration load_ros2_imu_calibration(const std::filesystem::path& imu_file,
                                         const std::filesystem::path& extrinsic_file);

// The readings of a ROS 2 IMU topic as imu/readings batches under the ordering contract (docs/topics.md):
// a batch's watermark is its last reading's stamp, and a frame with stamp t may go out once
// watermark_ns() >= t. Readings come one message each, in stamp order.
class ImuForwarder {
 public:
  struct Batch {
    std::vector<ImuSample> samples;
    std::uint64_t first_index = 0;  // stream index of samples[0]
    std::int64_t watermark_ns = 0;
  };

  // Throws std::runtime_error (nothing changed) for a stamp at or before the watermark: a stamp going
  // backwards, a repeated reading, or one that came after a frame was let go without it (silent_until).
  void add(const ImuSample& sample);
  // The readings added since the last batch; nullopt when there are none.
  std::optional<Batch> take_batch();
  // No reading will be taken at or before stamp_ns (a frame waited too long for the IMU): the batch that
  // says so (empty, watermark stamp_ns), which first carries the readings not yet taken.
  Batch silent_until(std::int64_t stamp_ns);
  std::int64_t watermark_ns() const { return watermark_ns_; }
  std::uint64_t taken() const { return next_index_; }

 private:
  std::vector<ImuSample> pending_;
  std::int64_t last_stamp_ns_ = INT64_MIN;
  std::int64_t watermark_ns_ = INT64_MIN;
  std::uint64_t next_index_ = 0;
};

}  // namespace heslam::ros2

// ROS 2 camera topics -> heslam's camera input, DDS-free so they are unit-tested on known values (the
// conversions of a ROS 2 stereo input; docs/ros2.md, ROS 2 input):
// - two sensor_msgs/CameraInfo (left, right) -> heslam's StereoCalibration. ROS 2's CameraInfo always
//   describes the raw camera: K, D (plumb_bob k1 k2 p1 p2 k3, or rational_polynomial k1..k6 p1 p2
//   whose k4..k6 are 0), the rectifying rotation R and the rectified projection P (the right one's
//   P[0][3] = -fx * baseline). For raw images this becomes an explicit rectification (as ORB-SLAM2's
//   LEFT.K/D/R/P); for images already rectified (image_proc's image_rect) the rectified pinhole P.
// - sensor_msgs/Image mono8 / bgr8 / rgb8 -> packed MONO8 or BGR8 pixels (rgb8 reordered), refusing
//   every other encoding, a step or data size that disagrees, or a size that is not the CameraInfo's.
// Every refusal is a std::runtime_error whose what() is one line naming the topic and the field.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "components/core/camera/stereo_calibration.hpp"
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

}  // namespace heslam::ros2

// Dataset values -> DDS messages for the replay (the thin adapter between heslam_dataset and the
// IDL types). Messages borrow their buffers: no image copy.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/camera/stereo_calibration.hpp"
#include "runtime/messages.hpp"
#include "tools/dataset/stereo_images.hpp"

namespace heslam {

// A msg::StereoCalibration and the buffers it points into (so neither copy nor move).
class CalibrationMessage {
 public:
  // rectified: the model the publisher's StereoRectifier derived, published for consumers to check.
  CalibrationMessage(const StereoCalibration& calibration, const PinholeStereo& rectified);
  CalibrationMessage(const CalibrationMessage&) = delete;
  CalibrationMessage& operator=(const CalibrationMessage&) = delete;

  const msg::StereoCalibration& get() const { return message_; }

 private:
  std::vector<double> left_distortion_;
  std::vector<double> right_distortion_;
  std::string source_;
  msg::StereoCalibration message_{};
};

// A StereoFrame pointing at the images' pixels; `images` must stay alive and unchanged until the
// write returns. Images must be continuous (cv::imread's are).
msg::StereoFrame make_frame_message(const StereoImages& images, std::int64_t stamp_ns, std::int64_t right_stamp_ns,
                                    std::uint64_t seq);

}  // namespace heslam

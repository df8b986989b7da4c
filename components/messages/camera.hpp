// Camera input on the wire: the calibration the replay publishes, the rectified camera a keyframe
// carries, and the images of a stereo frame, as core types.
#pragma once

#include <opencv2/core.hpp>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/camera/stereo_calibration.hpp"
#include "runtime/messages.hpp"

namespace heslam::messages {

// Throws std::runtime_error naming the calibration source and field when the message is unusable.
StereoCalibration to_calibration(const msg::StereoCalibration& message);
PinholeStereo to_camera(const msg::RectifiedStereoCamera& message);
msg::RectifiedStereoCamera to_message(const PinholeStereo& camera);

// The raw images of a frame as 8-bit grey. MONO8 pixels are wrapped without a copy (valid while the
// message lives); BGR8 is converted. Throws std::runtime_error naming the frame when the byte counts
// do not match width x height x channels.
struct GreyPair {
  cv::Mat left;
  cv::Mat right;
};
GreyPair to_grey_images(const msg::StereoFrame& frame);

}  // namespace heslam::messages

// Calibration, rectified camera and stereo images <-> core types (see camera.hpp).
#include "components/messages/camera.hpp"

#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "components/core/camera/image_limits.hpp"
#include "components/messages/checks.hpp"
#include "runtime/sequence.hpp"
#include "runtime/wire_enum.hpp"

namespace heslam::messages {
namespace {

template <typename Matrix, std::size_t N>
void from_row_major(const double (&values)[N], Matrix& matrix) {
  std::size_t i = 0;
  for (int r = 0; r < matrix.rows(); ++r)
    for (int c = 0; c < matrix.cols(); ++c) matrix(r, c) = values[i++];
}

CameraModel to_camera_model(const msg::CameraModel& message, const std::string& source, const char* which) {
  if (!image_size_plausible(message.width_px, message.height_px)) {
    throw std::runtime_error("calibration '" + source + "': " + which + ": image size " +
                             std::to_string(message.width_px) + "x" + std::to_string(message.height_px) + ": " +
                             image_size_expectation());
  }
  CameraModel camera;
  camera.width_px = static_cast<int>(message.width_px);
  camera.height_px = static_cast<int>(message.height_px);
  camera.fx_px = message.fx_px;
  camera.fy_px = message.fy_px;
  camera.cx_px = message.cx_px;
  camera.cy_px = message.cy_px;
  if (camera.width_px <= 0 || camera.height_px <= 0 || camera.fx_px <= 0.0 || camera.fy_px <= 0.0) {
    throw std::runtime_error("calibration '" + source + "': " + which +
                             ": expected a positive image size and focal length");
  }
  switch (runtime::wire_value(message.distortion_model)) {  // any value may come (runtime/wire_enum.hpp)
    case heslam_msg_DISTORTION_NONE: camera.distortion_model = DistortionModel::kNone; break;
    case heslam_msg_DISTORTION_RADIAL_TANGENTIAL: camera.distortion_model = DistortionModel::kRadialTangential; break;
    case heslam_msg_DISTORTION_EQUIDISTANT: camera.distortion_model = DistortionModel::kEquidistant; break;
    default:
      throw std::runtime_error("calibration '" + source + "': " + which + ".distortion_model: unknown value " +
                               std::to_string(runtime::wire_value(message.distortion_model)));
  }
  const auto distortion = runtime::view(message.distortion);
  camera.distortion.assign(distortion.begin(), distortion.end());
  Eigen::Matrix4d T_BS;
  from_row_major(message.T_BS, T_BS);
  camera.T_BS.matrix() = T_BS;
  return camera;
}

}  // namespace

StereoCalibration to_calibration(const msg::StereoCalibration& message) {
  StereoCalibration calibration;
  calibration.source = runtime::to_string(message.source);
  const std::string source = calibration.source.empty() ? "<unnamed>" : calibration.source;
  calibration.left = to_camera_model(message.left, source, "left");
  calibration.right = to_camera_model(message.right, source, "right");
  calibration.input_rectified = message.input_rectified;
  if (message.has_explicit_rectification) {
    ExplicitRectification rectification;
    from_row_major(message.explicit_rectification.R_left, rectification.R_left);
    from_row_major(message.explicit_rectification.R_right, rectification.R_right);
    from_row_major(message.explicit_rectification.P_left, rectification.P_left);
    from_row_major(message.explicit_rectification.P_right, rectification.P_right);
    calibration.explicit_rectification = rectification;
  }
  calibration.rate_hz = message.rate_hz;
  return calibration;
}

PinholeStereo to_camera(const msg::RectifiedStereoCamera& message) {
  PinholeStereo camera;
  camera.fx_px = message.fx_px;
  camera.fy_px = message.fy_px;
  camera.cx_px = message.cx_px;
  camera.cy_px = message.cy_px;
  camera.baseline_m = message.baseline_m;
  camera.width_px = static_cast<int>(message.width_px);
  camera.height_px = static_cast<int>(message.height_px);
  return camera;
}

msg::RectifiedStereoCamera to_message(const PinholeStereo& camera) {
  msg::RectifiedStereoCamera message{};
  message.fx_px = camera.fx_px;
  message.fy_px = camera.fy_px;
  message.cx_px = camera.cx_px;
  message.cy_px = camera.cy_px;
  message.baseline_m = camera.baseline_m;
  message.width_px = static_cast<std::uint32_t>(camera.width_px);
  message.height_px = static_cast<std::uint32_t>(camera.height_px);
  return message;
}

GreyPair to_grey_images(const msg::StereoFrame& frame) {
  if (auto problem = check(frame))
    throw std::runtime_error("stereo frame " + std::to_string(frame.seq) + ": " + *problem);
  const int width = static_cast<int>(frame.width_px);
  const int height = static_cast<int>(frame.height_px);
  const int channels = frame.encoding == heslam_msg_ENCODING_BGR8 ? 3 : 1;
  const auto left = runtime::view(frame.left);
  const auto right = runtime::view(frame.right);
  const int type = channels == 1 ? CV_8UC1 : CV_8UC3;
  // cv::Mat wraps non-const data; the pixels are only read.
  cv::Mat left_raw(height, width, type, const_cast<std::uint8_t*>(left.data()));
  cv::Mat right_raw(height, width, type, const_cast<std::uint8_t*>(right.data()));
  GreyPair pair;
  if (channels == 1) {
    pair.left = left_raw;
    pair.right = right_raw;
  } else {
    cv::cvtColor(left_raw, pair.left, cv::COLOR_BGR2GRAY);
    cv::cvtColor(right_raw, pair.right, cv::COLOR_BGR2GRAY);
  }
  return pair;
}

}  // namespace heslam::messages

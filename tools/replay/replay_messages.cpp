// Filling the IDL calibration and frame messages from the dataset's values.
#include "tools/replay/replay_messages.hpp"

#include <span>
#include <stdexcept>

#include "runtime/sequence.hpp"

namespace heslam {

namespace {

template <typename Matrix, std::size_t N>
void row_major(const Matrix& matrix, double (&out)[N]) {
  std::size_t i = 0;
  for (int r = 0; r < matrix.rows(); ++r)
    for (int c = 0; c < matrix.cols(); ++c) out[i++] = matrix(r, c);
}

void fill_camera(const CameraModel& camera, std::vector<double>& distortion, msg::CameraModel& out) {
  out.width_px = static_cast<std::uint32_t>(camera.width_px);
  out.height_px = static_cast<std::uint32_t>(camera.height_px);
  out.fx_px = camera.fx_px;
  out.fy_px = camera.fy_px;
  out.cx_px = camera.cx_px;
  out.cy_px = camera.cy_px;
  switch (camera.distortion_model) {
    case DistortionModel::kNone: out.distortion_model = heslam_msg_DISTORTION_NONE; break;
    case DistortionModel::kRadialTangential: out.distortion_model = heslam_msg_DISTORTION_RADIAL_TANGENTIAL; break;
    case DistortionModel::kEquidistant: out.distortion_model = heslam_msg_DISTORTION_EQUIDISTANT; break;
  }
  distortion = camera.distortion;
  runtime::borrow(out.distortion, distortion);
  row_major(camera.T_BS.matrix(), out.T_BS);
}

}  // namespace

CalibrationMessage::CalibrationMessage(const StereoCalibration& calibration, const PinholeStereo& rectified)
    : source_(calibration.source) {
  fill_camera(calibration.left, left_distortion_, message_.left);
  fill_camera(calibration.right, right_distortion_, message_.right);
  message_.input_rectified = calibration.input_rectified;
  message_.has_explicit_rectification = calibration.explicit_rectification.has_value();
  if (calibration.explicit_rectification) {
    const ExplicitRectification& explicit_rectification = *calibration.explicit_rectification;
    row_major(explicit_rectification.R_left, message_.explicit_rectification.R_left);
    row_major(explicit_rectification.R_right, message_.explicit_rectification.R_right);
    row_major(explicit_rectification.P_left, message_.explicit_rectification.P_left);
    row_major(explicit_rectification.P_right, message_.explicit_rectification.P_right);
  }
  message_.rectified.fx_px = rectified.fx_px;
  message_.rectified.fy_px = rectified.fy_px;
  message_.rectified.cx_px = rectified.cx_px;
  message_.rectified.cy_px = rectified.cy_px;
  message_.rectified.baseline_m = rectified.baseline_m;
  message_.rectified.width_px = static_cast<std::uint32_t>(rectified.width_px);
  message_.rectified.height_px = static_cast<std::uint32_t>(rectified.height_px);
  message_.rate_hz = calibration.rate_hz;
  message_.source = runtime::borrow(source_);
}

msg::StereoFrame make_frame_message(const StereoImages& images, std::int64_t stamp_ns, std::int64_t right_stamp_ns,
                                    std::uint64_t seq) {
  if (!images.left.isContinuous() || !images.right.isContinuous()) {
    throw std::runtime_error("stereo frame " + std::to_string(seq) + ": image rows are not contiguous");
  }
  msg::StereoFrame frame{};
  frame.stamp_ns = stamp_ns;
  frame.stamp_right_ns = right_stamp_ns;
  frame.seq = seq;
  frame.width_px = static_cast<std::uint32_t>(images.left.cols);
  frame.height_px = static_cast<std::uint32_t>(images.left.rows);
  frame.encoding = images.encoding == "bgr8" ? heslam_msg_ENCODING_BGR8 : heslam_msg_ENCODING_MONO8;
  const auto bytes_of = [](const cv::Mat& image) {
    return std::span<const std::uint8_t>(image.data, image.total() * image.elemSize());
  };
  runtime::borrow(frame.left, bytes_of(images.left));
  runtime::borrow(frame.right, bytes_of(images.right));
  return frame;
}

}  // namespace heslam

// Stereo rectification: the rectified model and remap tables from a StereoCalibration.
#include "components/core/camera/stereo_rectifier.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "components/core/camera/image_limits.hpp"

namespace heslam {
namespace {

// alpha 0: the rectified image holds only valid pixels (no black borders), as ORB-SLAM2's EuRoC.yaml.
constexpr double kRectifyAlpha = 0.0;
// Fisheye pairs: balance 0 picks the larger of OpenCV's two focal lengths (the undistorted image's edge
// midpoints inside the raw image), the fisheye counterpart of alpha 0; fov_scale 1 keeps it.
constexpr double kFisheyeBalance = 0.0;
constexpr double kFisheyeFovScale = 1.0;

cv::Mat camera_matrix(const CameraModel& c) {
  return (cv::Mat_<double>(3, 3) << c.fx_px, 0.0, c.cx_px, 0.0, c.fy_px, c.cy_px, 0.0, 0.0, 1.0);
}

cv::Mat distortion_vector(const CameraModel& c) {
  if (c.distortion_model == DistortionModel::kNone) return cv::Mat();
  return cv::Mat(c.distortion, /*copyData=*/true).reshape(1, 1);
}

template <int R, int C>
cv::Mat to_cv(const Eigen::Matrix<double, R, C>& m) {
  cv::Mat out(R, C, CV_64F);
  for (int r = 0; r < R; ++r)
    for (int c = 0; c < C; ++c) out.at<double>(r, c) = m(r, c);
  return out;
}

Eigen::Matrix3d to_eigen3(const cv::Mat& m) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = m.at<double>(r, c);
  return out;
}

void check_image(const cv::Mat& image, cv::Size expected, const char* which) {
  if (image.type() != CV_8UC1 || image.size() != expected) {
    throw std::runtime_error(std::string("StereoRectifier: ") + which + " image is " + std::to_string(image.cols) +
                             "x" + std::to_string(image.rows) + " type " + std::to_string(image.type()) +
                             ", expected " + std::to_string(expected.width) + "x" + std::to_string(expected.height) +
                             " 8-bit grey");
  }
}

// Every number of the calibration is finite, or one line naming the camera and the field.
void check_finite(const StereoCalibration& calibration) {
  const auto check = [&](const std::string& field, bool finite) {
    if (!finite)
      throw std::runtime_error(calibration.source + ": " + field + ": expected finite numbers, got a nan or inf");
  };
  for (const auto& [camera, which] : {std::pair{&calibration.left, "left"}, std::pair{&calibration.right, "right"}}) {
    const std::string name = std::string(which) + " camera";
    check(name + " fx_px", std::isfinite(camera->fx_px));
    check(name + " fy_px", std::isfinite(camera->fy_px));
    check(name + " cx_px", std::isfinite(camera->cx_px));
    check(name + " cy_px", std::isfinite(camera->cy_px));
    for (std::size_t i = 0; i < camera->distortion.size(); ++i) {
      check(name + " distortion coefficient " + std::to_string(i), std::isfinite(camera->distortion[i]));
    }
    check(name + " T_BS", camera->T_BS.matrix().allFinite());
    if (camera->distortion_model == DistortionModel::kEquidistant && camera->distortion.size() != 4) {
      throw std::runtime_error(calibration.source + ": " + name + " distortion: expected 4 equidistant coefficients " +
                               "k1 k2 k3 k4, got " + std::to_string(camera->distortion.size()));
    }
  }
  if (const auto& e = calibration.explicit_rectification) {
    check("rectification R_left", e->R_left.allFinite());
    check("rectification R_right", e->R_right.allFinite());
    check("rectification P_left", e->P_left.allFinite());
    check("rectification P_right", e->P_right.allFinite());
  }
}

}  // namespace

StereoRectifier::StereoRectifier(const StereoCalibration& calibration) {
  const CameraModel& left = calibration.left;
  const CameraModel& right = calibration.right;
  // First: a nan anywhere turns every later check (the baseline's sign among them) into a wrong
  // message. A calibration from the topic has not been through the file readers' checks.
  check_finite(calibration);
  if (left.width_px <= 0 || left.height_px <= 0 || !(left.fx_px > 0.0) || !(left.fy_px > 0.0)) {
    throw std::runtime_error(calibration.source + ": left camera: expected positive size and focal lengths");
  }
  for (const auto& [camera, which] : {std::pair{&left, "left"}, std::pair{&right, "right"}}) {
    if (!image_size_plausible(static_cast<std::uint64_t>(std::max(camera->width_px, 0)),
                              static_cast<std::uint64_t>(std::max(camera->height_px, 0)))) {
      throw std::runtime_error(calibration.source + ": " + which + " camera: image size " +
                               std::to_string(camera->width_px) + "x" + std::to_string(camera->height_px) + ": " +
                               image_size_expectation());
    }
  }
  raw_size_ = cv::Size(left.width_px, left.height_px);
  camera_.width_px = left.width_px;
  camera_.height_px = left.height_px;

  if (calibration.input_rectified) {
    const Eigen::Vector3d t_rl = calibration.T_rl().translation();
    camera_.fx_px = left.fx_px;
    camera_.fy_px = left.fy_px;
    camera_.cx_px = left.cx_px;
    camera_.cy_px = left.cy_px;
    camera_.baseline_m = -t_rl.x();
    T_B_rect_ = left.T_BS;
    passthrough_ = true;
  } else {
    try {
      compute_rectification(calibration);
    } catch (const cv::Exception& error) {
      // OpenCV's own text names its source file and function, not the calibration at fault.
      throw std::runtime_error(calibration.source + ": cannot rectify with this calibration (OpenCV: " + error.err +
                               ")");
    }
  }
  if (!(camera_.baseline_m > 0.0)) {
    throw std::runtime_error(calibration.source +
                             ": right camera: expected it to the right of the left camera (positive baseline)");
  }
}

void StereoRectifier::compute_rectification(const StereoCalibration& calibration) {
  const CameraModel& left = calibration.left;
  const CameraModel& right = calibration.right;
  const bool fisheye = left.distortion_model == DistortionModel::kEquidistant;
  if (fisheye != (right.distortion_model == DistortionModel::kEquidistant)) {
    throw std::runtime_error(calibration.source + ": left camera " + to_string(left.distortion_model) +
                             ", right camera " + to_string(right.distortion_model) +
                             ": expected both equidistant (fisheye) or neither");
  }
  {
    cv::Mat R1, R2, P1, P2;
    if (calibration.explicit_rectification) {
      const ExplicitRectification& e = *calibration.explicit_rectification;
      R1 = to_cv(e.R_left);
      R2 = to_cv(e.R_right);
      P1 = to_cv(e.P_left);
      P2 = to_cv(e.P_right);
    } else if (fisheye) {
      const Pose3 T_rl = calibration.T_rl();
      const cv::Mat R = to_cv(Eigen::Matrix3d(T_rl.linear()));
      const cv::Mat T = to_cv(Eigen::Matrix<double, 3, 1>(T_rl.translation()));
      cv::Mat Q;
      cv::fisheye::stereoRectify(camera_matrix(left), distortion_vector(left), camera_matrix(right),
                                 distortion_vector(right), raw_size_, R, T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY,
                                 raw_size_, kFisheyeBalance, kFisheyeFovScale);
    } else {
      const Pose3 T_rl = calibration.T_rl();
      const cv::Mat R = to_cv(Eigen::Matrix3d(T_rl.linear()));
      const cv::Mat T = to_cv(Eigen::Matrix<double, 3, 1>(T_rl.translation()));
      cv::Mat Q;
      cv::stereoRectify(camera_matrix(left), distortion_vector(left), camera_matrix(right), distortion_vector(right),
                        raw_size_, R, T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY, kRectifyAlpha, raw_size_);
    }
    camera_.fx_px = P1.at<double>(0, 0);
    camera_.fy_px = P1.at<double>(1, 1);
    camera_.cx_px = P1.at<double>(0, 2);
    camera_.cy_px = P1.at<double>(1, 2);
    camera_.baseline_m = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
    // p_rect = R1 p_cam0, so rect -> body is T_BS(cam0) * R1^T.
    Pose3 T_cam0_rect = Pose3::Identity();
    T_cam0_rect.linear() = to_eigen3(R1).transpose();
    T_B_rect_ = left.T_BS * T_cam0_rect;
    if (fisheye) {
      cv::fisheye::initUndistortRectifyMap(camera_matrix(left), distortion_vector(left), R1, P1.colRange(0, 3),
                                           raw_size_, CV_16SC2, left_map_xy_, left_map_frac_);
      cv::fisheye::initUndistortRectifyMap(camera_matrix(right), distortion_vector(right), R2, P2.colRange(0, 3),
                                           cv::Size(right.width_px, right.height_px), CV_16SC2, right_map_xy_,
                                           right_map_frac_);
    } else {
      cv::initUndistortRectifyMap(camera_matrix(left), distortion_vector(left), R1, P1.colRange(0, 3), raw_size_,
                                  CV_16SC2, left_map_xy_, left_map_frac_);
      cv::initUndistortRectifyMap(camera_matrix(right), distortion_vector(right), R2, P2.colRange(0, 3),
                                  cv::Size(right.width_px, right.height_px), CV_16SC2, right_map_xy_, right_map_frac_);
    }
  }
  left_remap_ = BilinearRemap(left_map_xy_, left_map_frac_, raw_size_);
  right_remap_ = BilinearRemap(right_map_xy_, right_map_frac_, cv::Size(right.width_px, right.height_px));
}

void StereoRectifier::rectify(const cv::Mat& left_raw, const cv::Mat& right_raw, cv::Mat& left_rect,
                              cv::Mat& right_rect) const {
  check_image(left_raw, raw_size_, "left");
  check_image(right_raw, raw_size_, "right");
  if (passthrough_) {
    left_rect = left_raw;
    right_rect = right_raw;
    return;
  }
  // cv::remap itself (each image spread over OpenCV's pool): the reference rectify_left / right match.
  cv::remap(left_raw, left_rect, left_map_xy_, left_map_frac_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::remap(right_raw, right_rect, right_map_xy_, right_map_frac_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
}

void StereoRectifier::rectify_left(const cv::Mat& left_raw, cv::Mat& left_rect) const {
  check_image(left_raw, raw_size_, "left");
  if (passthrough_) {
    left_rect = left_raw;
    return;
  }
  left_remap_.apply(left_raw, left_rect);
}

void StereoRectifier::rectify_right(const cv::Mat& right_raw, cv::Mat& right_rect) const {
  check_image(right_raw, raw_size_, "right");
  if (passthrough_) {
    right_rect = right_raw;
    return;
  }
  right_remap_.apply(right_raw, right_rect);
}

}  // namespace heslam

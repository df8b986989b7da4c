// Clip-edge marks of stereo matches: plateau masks and one integral image per image, O(1) per match.
#include "components/core/match/clip_edge.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace heslam {
namespace {

// Clipped pixels in the box [u - r, u + r] x [v - r, v + r] (clamped to the image) from the
// integral image of a 0/1 mask.
int clipped_in_box(const cv::Mat& integral, float u_px, float v_px, float r_px) {
  const int cols = integral.cols - 1;
  const int rows = integral.rows - 1;
  const int x0 = std::clamp(static_cast<int>(std::floor(u_px - r_px)), 0, cols);
  const int x1 = std::clamp(static_cast<int>(std::ceil(u_px + r_px)) + 1, 0, cols);
  const int y0 = std::clamp(static_cast<int>(std::floor(v_px - r_px)), 0, rows);
  const int y1 = std::clamp(static_cast<int>(std::ceil(v_px + r_px)) + 1, 0, rows);
  if (x1 <= x0 || y1 <= y0) return 0;
  return integral.at<int>(y1, x1) - integral.at<int>(y0, x1) - integral.at<int>(y1, x0) + integral.at<int>(y0, x0);
}

}  // namespace

int clipped_top_level(const cv::Mat& grey, double min_clipped_fraction) {
  if (grey.type() != CV_8UC1 || grey.empty())
    throw std::invalid_argument("clipped_top_level: expected an 8-bit grey image");
  double low = 0.0;
  double high = 0.0;
  cv::minMaxLoc(grey, &low, &high);
  const double min_count = min_clipped_fraction * static_cast<double>(grey.total());
  return cv::countNonZero(grey == high) >= min_count ? static_cast<int>(high) : 256;
}

cv::Mat clipped_pixel_mask(const cv::Mat& grey, double min_clipped_fraction) {
  if (grey.type() != CV_8UC1 || grey.empty())
    throw std::invalid_argument("clipped_pixel_mask: expected an 8-bit grey image");
  cv::Mat mask = cv::Mat::zeros(grey.size(), CV_8UC1);
  double low = 0.0;
  double high = 0.0;
  cv::minMaxLoc(grey, &low, &high);
  const double min_count = min_clipped_fraction * static_cast<double>(grey.total());
  for (const double level : {high, low}) {
    const cv::Mat at_level = grey == level;
    if (cv::countNonZero(at_level) >= min_count) mask.setTo(1, at_level);
  }
  return mask;
}

void mark_near_clip(const cv::Mat& left_clipped, const cv::Mat& right_clipped, const ClipEdgeOptions& options,
                    StereoFeatures& features) {
  const std::size_t n = features.size();
  features.near_clip.assign(n, 0);
  if (options.radius_px <= 0) return;
  if (left_clipped.size() != right_clipped.size() || left_clipped.type() != CV_8UC1 ||
      right_clipped.type() != CV_8UC1) {
    throw std::invalid_argument("mark_near_clip: expected two 8-bit masks of one size");
  }
  const bool any_left = cv::countNonZero(left_clipped) > 0;
  const bool any_right = cv::countNonZero(right_clipped) > 0;
  if (!any_left && !any_right) return;
  cv::Mat left_integral;
  cv::Mat right_integral;
  cv::integral(left_clipped, left_integral, CV_32S);
  cv::integral(right_clipped, right_integral, CV_32S);
  for (std::size_t i = 0; i < n; ++i) {
    if (!features.has_stereo(i)) continue;
    const Keypoint& kp = features.keypoints[i];
    const float r_px =
        static_cast<float>(options.radius_px) * features.pyramid.scale[static_cast<std::size_t>(kp.octave)];
    const bool near = (any_left && clipped_in_box(left_integral, kp.u_px, kp.v_px, r_px) > 0) ||
                      (any_right && clipped_in_box(right_integral, features.u_right_px[i], kp.v_px, r_px) > 0);
    features.near_clip[i] = near ? 1 : 0;
  }
}

}  // namespace heslam

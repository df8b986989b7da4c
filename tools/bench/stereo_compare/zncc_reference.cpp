// ZNCC reference disparity (zncc_reference.hpp).
#include "tools/bench/stereo_compare/zncc_reference.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace heslam::bench {

std::optional<double> zncc_reference_disparity(const cv::Mat& left, const cv::Mat& right, float u_px, float v_px,
                                               int half, double guess_px) {
  const int u0 = static_cast<int>(std::lround(u_px)), v0 = static_cast<int>(std::lround(v_px));
  if (v0 - half < 0 || v0 + half >= left.rows || u0 - half < 0 || u0 + half >= left.cols) return std::nullopt;
  cv::Mat window_left;
  left(cv::Rect(u0 - half, v0 - half, 2 * half + 1, 2 * half + 1)).convertTo(window_left, CV_32F);
  cv::Scalar mean_left, std_left;
  cv::meanStdDev(window_left, mean_left, std_left);
  if (std_left[0] < kMinWindowStdDev) return std::nullopt;
  window_left -= mean_left[0];
  const int first = static_cast<int>(std::floor(guess_px)) - kReferenceSearchPx;
  const int last = static_cast<int>(std::ceil(guess_px)) + kReferenceSearchPx;
  std::vector<double> score;
  for (int d = first; d <= last; ++d) {
    const int u_right = u0 - d;
    if (u_right - half < 0 || u_right + half >= right.cols) return std::nullopt;
    cv::Mat window_right;
    right(cv::Rect(u_right - half, v0 - half, 2 * half + 1, 2 * half + 1)).convertTo(window_right, CV_32F);
    cv::Scalar mean_right, std_right;
    cv::meanStdDev(window_right, mean_right, std_right);
    if (std_right[0] <= 0.0) {
      score.push_back(-1.0);
      continue;
    }
    score.push_back(window_left.dot(window_right - mean_right[0]) /
                    (std_left[0] * std_right[0] * static_cast<double>(window_left.total())));
  }
  const auto best = static_cast<std::size_t>(std::max_element(score.begin(), score.end()) - score.begin());
  if (best == 0 || best + 1 == score.size() || score[best] < kMinPeakZncc) return std::nullopt;
  const double curvature = score[best - 1] - 2.0 * score[best] + score[best + 1];
  if (curvature >= 0.0) return std::nullopt;
  // The window is centred on the rounded u: the keypoint's own fraction moves the disparity with it.
  return first + static_cast<double>(best) + 0.5 * (score[best - 1] - score[best + 1]) / curvature +
         (u_px - static_cast<float>(u0));
}

}  // namespace heslam::bench

// A reference disparity for a stereo keypoint, for the exposure benches: ZNCC block matching at the
// keypoint's left pixel in another (well exposed) rectified pair of the same frame.
#pragma once

#include <optional>

#include <opencv2/core.hpp>

namespace heslam::bench {

// Kept where the reference is trustworthy: a textured left window, a clear ZNCC peak inside the search.
inline constexpr double kMinWindowStdDev = 2.0;  // grey levels
inline constexpr double kMinPeakZncc = 0.9;
inline constexpr int kReferenceSearchPx = 4;  // +- around the guess
// A stereo match further than this from its reference disagrees on the match, not on its position.
inline constexpr double kMaxReferenceDiffPx = 3.0;

// Disparity (u_left - u_right, level-0 pixels) at left pixel (u, v) by ZNCC of a (2 half + 1)^2 window
// over whole-pixel disparities around `guess_px`, parabola through the peak; nothing where the window
// is flat, the peak weak or on the edge of the search.
std::optional<double> zncc_reference_disparity(const cv::Mat& left, const cv::Mat& right, float u_px, float v_px,
                                               int half, double guess_px);

}  // namespace heslam::bench

// Stereo matches near a clip edge: where one camera of a pair exposed apart saturates, the edge of
// the saturated area lies where that camera's exposure put it, not on the scene, so a SAD (or any)
// window that contains it pulls the disparity towards the two edges' offset
// (heslam-bench-stereo-compare: 29 % of such matches off by > 0.5 px at left x0.35 / right x2,
// 7 % clear of them). This marks them, so that tracking can trust their disparity less.
#pragma once

#include <opencv2/core.hpp>

#include "components/core/feature/features.hpp"

namespace heslam {

struct ClipEdgeOptions {
  // Half size (pixels on the keypoint's pyramid level) of the box around the left keypoint and around
  // its right match in which a clipped pixel marks the match: the SAD window's 5 plus one for the
  // subpixel neighbours. 0 marks nothing.
  int radius_px = 6;
  // An image counts as clipped when at least this fraction of it sits at its top (or bottom) grey
  // level: equally exposed EuRoC MH01 images saturate 3-6 %, right x1.5 17-35 %.
  double min_clipped_fraction = 0.01;

  bool operator==(const ClipEdgeOptions&) const = default;
};

// The image's top grey level when at least min_clipped_fraction of its pixels sit there (its
// saturated plateau), else 256.
int clipped_top_level(const cv::Mat& grey, double min_clipped_fraction);

// 8-bit mask (1 = clipped) of the pixels at the image's top and bottom grey level, each only when that
// level holds at least min_clipped_fraction of the image; all zeros when neither does.
cv::Mat clipped_pixel_mask(const cv::Mat& grey, double min_clipped_fraction);

// Sets features.near_clip (one entry per keypoint) from the masks of the two images the matching saw
// (the equalized pair): 1 for a stereo match with a clipped pixel in the box around the left keypoint
// or around (u_right, v) in the right image; 0 elsewhere.
void mark_near_clip(const cv::Mat& left_clipped, const cv::Mat& right_clipped, const ClipEdgeOptions& options,
                    StereoFeatures& features);

}  // namespace heslam

// FAST-9 (16-pixel circle) corner scores of every pixel of an image area, computed with SIMD in one
// pass, and corner lists read from them exactly as cv::FAST (with non-maximum suppression) would
// report them on a sub-image. ORB-SLAM2's gridded detection calls FAST twice (threshold 20 over the
// image, then threshold 7 in every cell that found nothing); with the scores of all pixels at hand both
// become a scan of the map, and OpenCV's scalar per-corner scoring disappears.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/feature/quadtree_distribution.hpp"

namespace heslam {

class FastScoreMap {
 public:
  // Radius of FAST's Bresenham circle: `image` must be readable this far around `area`.
  static constexpr int kRadiusPx = 3;

  // Scores every pixel of `area` (8-bit grey `image`). A pixel is a FAST corner at threshold t
  // (9 contiguous circle pixels all brighter than centre + t, or all darker than centre - t) exactly
  // when its score is >= t; the score is cv::FAST's response (OpenCV's cornerScore).
  void compute(const cv::Mat& image, const cv::Rect& area);

  // Appends, in row-major order, the corners with score >= threshold (>= 1) inside `region` (a part
  // of the scored area) that survive 3x3 non-maximum suppression among the region's own pixels:
  // the same points and responses as cv::FAST(image(region grown by kRadiusPx), threshold, true).
  void corners(const cv::Rect& region, int threshold, std::vector<ScoredPoint>& out) const;

  // The score of a pixel of the area (image coordinates).
  std::uint8_t score(int x, int y) const {
    return score_[static_cast<std::size_t>(y - area_.y) * static_cast<std::size_t>(area_.width) +
                  static_cast<std::size_t>(x - area_.x)];
  }

 private:
  cv::Rect area_;
  std::vector<std::uint8_t> score_;  // area_.width x area_.height, row-major
};

}  // namespace heslam

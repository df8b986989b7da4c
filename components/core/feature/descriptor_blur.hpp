// The 7x7 Gaussian (sigma 2) that smooths each pyramid level before rBRIEF sampling, bit-exact with
// cv::GaussianBlur(src, dst, {7, 7}, 2, 2) on 8-bit images, but computed only over the part of the
// level the descriptors read, with SIMD integer arithmetic and no per-call allocation.
//
// OpenCV 4.6 computes that blur in fixed point: the kernel {18, 34, 48, 56, 48, 34, 18} / 256 in both
// directions and one rounding at the end, dst = (sum_ij k_i k_j p_ij + 2^15) >> 16. The sum is an
// exact integer, so its order does not matter. With AVX2 (regions of 32 pixels or more): a
// horizontal pass on the bytes (pmaddubsw) into 16-bit row sums of the halved kernel, kept for 7 rows,
// then a vertical pass in 32 bits (pmaddwd). Otherwise: a vertical pass into 16-bit sums (exact), then
// a horizontal pass whose 32-bit sum is taken as a high and a low byte part of 16 bits each.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace heslam {

class DescriptorBlur {
 public:
  // Half size of the kernel: `src` must be readable this far around the blurred region.
  static constexpr int kRadiusPx = 3;

  // Writes into `dst` (allocated or reused with src's size and type CV_8UC1) the blur of the pixels
  // of `region` (src coordinates); pixels of dst outside `region` are left as they were. `region`
  // grown by kRadiusPx must lie inside src (no border extrapolation happens here: pad src first).
  // The result equals cv::GaussianBlur(src, g, {7, 7}, 2, 2, BORDER_REFLECT_101)(region) exactly.
  // Not thread-safe (row scratch); use one per thread.
  void apply(const cv::Mat& src, const cv::Rect& region, cv::Mat& dst);

 private:
  // AVX2, regions at least 32 pixels wide: row sums first (a ring of 7 rows), then column sums.
  void apply_blocks(const cv::Mat& src, const cv::Rect& region, cv::Mat& dst);

  std::vector<std::uint16_t> column_sums_;  // the vertical pass of one output row (other cases)
  std::vector<std::int16_t> ring_;          // AVX2 path: biased row sums of 7 source rows
};

}  // namespace heslam

// Bilinear remapping of an 8-bit grey image with fixed-point maps, pixel for pixel what
// cv::remap(src, dst, map_xy, map_frac, INTER_LINEAR, BORDER_CONSTANT, 0) gives, in about a quarter of
// its instructions.
//
// cv::remap's 8-bit bilinear path is fixed point: map_xy (CV_16SC2) holds the integer source pixel
// (sx, sy), map_frac (CV_16UC1) the fraction in 1/32 px as fy * 32 + fx, and an output pixel is
// (sum of w_k * S_k + 2^14) >> 15 over the 2x2 neighbourhood, with the weights 32 * (32 - fx)(32 - fy),
// 32 * fx (32 - fy), 32 * (32 - fx) fy, 32 * fx fy; taps outside the image count as 0. (OpenCV stores
// the weight 32768 of an integer position as 32767 and moves the 1 to the opposite tap; for 8-bit
// pixels both give the pixel itself.) Dividing by 32: (sum of w'_k S_k + 512) >> 10 with
// w' = (32 - fx)(32 - fy), ..., which is what this computes.
//
// On the rectification of EuRoC pairs cv::remap spent about 36 instructions per pixel (26 M per pair,
// more than the whole tracking), this about 10, in less than half the CPU time (callgrind and thread
// CPU in docs/benchmarks.md at 5c1f792, Frontend critical path fourth pass). Blocks of 8 output pixels whose
// 2x2 neighbourhoods lie inside the image read them from one 16-byte window per half block (byte
// shuffles) or, where the map jumps, with two AVX2 gathers, then a few multiply-adds; the rest (image
// borders) use the scalar formula. Without AVX2, the scalar formula everywhere.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace heslam {

class BilinearRemap {
 public:
  BilinearRemap() = default;
  // map_xy: CV_16SC2, map_frac: CV_16UC1 of the output size (cv::initUndistortRectifyMap with
  // CV_16SC2); src_size: the size of the images to remap. Throws std::invalid_argument otherwise.
  BilinearRemap(const cv::Mat& map_xy, const cv::Mat& map_frac, cv::Size src_size);

  // src: 8-bit grey of src_size. dst is (re)allocated to the maps' size only if it is not already
  // that size and type, then every pixel written. Throws std::invalid_argument on another src.
  void apply(const cv::Mat& src, cv::Mat& dst) const;

  bool empty() const { return map_xy_.empty(); }

 private:
  cv::Mat map_xy_;
  cv::Mat map_frac_;
  cv::Size src_size_;
  // Per block of 8 output pixels of a row (row-major, blocks_per_row_ per row): how it is computed
  // (scalar, gathers, windows; see the .cpp) and, for windows, each half block's first source byte.
  std::vector<unsigned char> block_mode_;
  std::vector<std::int32_t> block_window_;
  int blocks_per_row_ = 0;
};

}  // namespace heslam

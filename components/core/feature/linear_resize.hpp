// Bilinear resize of 8-bit grey images, bit-exact with cv::resize(src, dst, size, 0, 0, INTER_LINEAR)
// of OpenCV 4.6, for the ORB pyramid: the per-column source offsets, weights and byte shuffles are
// planned once per (source, destination) size and reused every frame, and both passes run with AVX2.
//
// OpenCV 4.6 resizes CV_8U in fixed point: weights a = saturate_cast<short>(w * 2048) from float
// coordinates ((d + 0.5) * src / dst - 0.5, clamped to the image), a horizontal pass into exact 32-bit
// sums h = p0 a0 + p1 a1, and a vertical pass that keeps 16 bits of each row, dst = saturate((
// ((h0 >> 4) b0 >> 16) + ((h1 >> 4) b1 >> 16) + 2) >> 2) (its SIMD formula, which it uses for every
// column, the last ones too: checked against cv::resize in tests/vision/linear_resize_test.cpp).
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace heslam {

class LinearResize {
 public:
  // Writes the resize of `src` (CV_8UC1, not empty) into `dst`, which must already have its size and
  // type CV_8UC1 (e.g. a view into a padded buffer: it is not reallocated). Equals cv::resize(src,
  // r, dst.size(), 0, 0, cv::INTER_LINEAR) exactly. Not thread-safe (plan and row buffers); one per
  // thread.
  void apply(const cv::Mat& src, cv::Mat& dst);

 private:
  // Destination columns per horizontal SIMD block: their two source pixels must lie within one
  // 16-byte load (true for any downscale; upscales go the scalar way).
  static constexpr int kBlockColumns = 8;

  void plan(int src_width, int dst_width);
  void resize_row(const std::uint8_t* src_row, std::int16_t* out) const;
  std::int16_t horizontal(const std::uint8_t* src_row, int d) const;  // one column, scalar

  int src_width_ = 0;
  int dst_width_ = 0;
  std::vector<int> x_offset_;           // per destination column: its left source pixel
  std::vector<std::int16_t> x_weight_;  // per destination column: the weights of that pixel and the next
  int vector_blocks_ = 0;               // leading blocks of kBlockColumns columns done with SIMD
  std::vector<std::uint8_t> shuffle_;   // per SIMD block: 16 byte indices relative to its first pixel
  // The row's last 2 kBlockColumns columns as one more pair of blocks (overlapping the leading ones),
  // each loading the 16 bytes that end at the row's end when its first pixel is closer to it.
  bool tail_blocks_ = false;
  int tail_base_[2] = {0, 0};               // source pixel each tail block loads from
  std::vector<std::uint8_t> tail_shuffle_;  // 2 x 16 byte indices relative to tail_base_
  std::vector<std::int16_t> rows_[2];       // horizontal pass (h >> 4) of two source rows
  int row_y_[2] = {-1, -1};                 // the source row each buffer holds
};

}  // namespace heslam

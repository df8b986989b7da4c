// Bilinear resize (OpenCV 4.6's fixed-point INTER_LINEAR, bit-exact): a planned horizontal pass with
// byte shuffles and 16-bit multiply-adds, two cached source rows, and a 16-bit vertical pass.
#include "components/core/feature/linear_resize.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace heslam {
namespace {

// OpenCV's INTER_RESIZE_COEF_BITS: weights are fractions of 2^11.
constexpr float kWeightScale = 2048.f;

// Source coordinate of destination pixel d and its fraction, as cv::resize computes them: in double,
// then rounded to float (the fraction is taken in float).
struct SourceCoordinate {
  int index;
  float fraction;
};
SourceCoordinate source_coordinate(int d, double scale) {
  const auto f = static_cast<float>((d + 0.5) * scale - 0.5);
  const int index = static_cast<int>(std::floor(f));
  return {index, f - static_cast<float>(index)};
}

std::int16_t weight(float w) { return cv::saturate_cast<std::int16_t>(w * kWeightScale); }

// The vertical pass of one pixel: OpenCV's SIMD formula (16-bit high products, then a rounding shift).
std::uint8_t vertical(std::int16_t h0, std::int16_t h1, std::int16_t b0, std::int16_t b1) {
  const int sum = ((h0 * b0) >> 16) + ((h1 * b1) >> 16);
  return static_cast<std::uint8_t>(std::clamp((sum + 2) >> 2, 0, 255));
}

}  // namespace

void LinearResize::plan(int src_width, int dst_width) {
  src_width_ = src_width;
  dst_width_ = dst_width;
  const double scale = 1.0 / (static_cast<double>(dst_width) / src_width);
  x_offset_.resize(static_cast<std::size_t>(dst_width));
  x_weight_.resize(2 * static_cast<std::size_t>(dst_width));
  for (int d = 0; d < dst_width; ++d) {
    SourceCoordinate c = source_coordinate(d, scale);
    // Clamped at both ends with the whole weight on the edge pixel, as cv::resize does.
    if (c.index < 0) c = {0, 0.f};
    if (c.index >= src_width - 1) c = {src_width - 1, 0.f};
    x_offset_[d] = c.index;
    x_weight_[2 * d] = weight(1.f - c.fraction);
    x_weight_[2 * d + 1] = weight(c.fraction);
  }
  // SIMD blocks (pairs of them, for the 256-bit pack): each one 16-byte load from its first source
  // pixel, inside the row, holding both source pixels of its kBlockColumns columns.
  shuffle_.clear();
  int blocks = 0;
  for (int first = 0; first + kBlockColumns <= dst_width; first += kBlockColumns, ++blocks) {
    const int base = x_offset_[first];
    if (base + 16 > src_width || x_offset_[first + kBlockColumns - 1] + 1 - base > 15) break;
    for (int i = 0; i < kBlockColumns; ++i) {
      shuffle_.push_back(static_cast<std::uint8_t>(x_offset_[first + i] - base));
      shuffle_.push_back(static_cast<std::uint8_t>(x_offset_[first + i] - base + 1));
    }
  }
  vector_blocks_ = blocks & ~1;

  // The tail pair. A clamped last column (the whole weight on the row's last pixel, 0 on the next)
  // takes its own pixel as the "next" one: the same sum, and no byte past the row is read.
  tail_blocks_ = false;
  tail_shuffle_.clear();
  const int tail_first = dst_width - 2 * kBlockColumns;
  if (vector_blocks_ * kBlockColumns < dst_width && tail_first >= 0 && src_width >= 16) {
    bool fits = true;
    for (int k = 0; k < 2; ++k) {
      const int first = tail_first + k * kBlockColumns;
      const int base = std::min(x_offset_[first], src_width - 16);
      tail_base_[k] = base;
      for (int i = first; i < first + kBlockColumns; ++i) {
        const int left = x_offset_[i] - base;
        const int right = std::min(x_offset_[i] + 1, src_width - 1) - base;
        fits = fits && left >= 0 && right <= 15;
        tail_shuffle_.push_back(static_cast<std::uint8_t>(left));
        tail_shuffle_.push_back(static_cast<std::uint8_t>(right));
      }
    }
    tail_blocks_ = fits;
  }
}

#if defined(__AVX2__)
namespace {

// 2 x 8 destination columns from `first`: block k loads 16 bytes at src_row + base[k] and picks its
// pixel pairs with shuffle + 16 k.
[[gnu::always_inline]] inline void block_pair(const std::uint8_t* src_row, const int (&base)[2],
                                              const std::uint8_t* shuffle, const std::int16_t* weights,
                                              std::int16_t* out) {
  __m256i h[2];
  for (int k = 0; k < 2; ++k) {
    const __m128i bytes = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src_row + base[k]));
    const __m128i pairs = _mm_shuffle_epi8(bytes, _mm_loadu_si128(reinterpret_cast<const __m128i*>(shuffle + 16 * k)));
    const __m256i w = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(weights + 16 * k));
    h[k] = _mm256_srai_epi32(_mm256_madd_epi16(_mm256_cvtepu8_epi16(pairs), w), 4);
  }
  // packs works per 128-bit lane: 64-bit quarters (0, 2, 1, 3) restore the column order.
  const __m256i packed = _mm256_permute4x64_epi64(_mm256_packs_epi32(h[0], h[1]), 0xD8);
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), packed);
}

}  // namespace
#endif

void LinearResize::resize_row(const std::uint8_t* src_row, std::int16_t* out) const {
  int d = 0;
#if defined(__AVX2__)
  for (int b = 0; b < vector_blocks_; b += 2, d += 2 * kBlockColumns) {
    const int base[2] = {x_offset_[d], x_offset_[d + kBlockColumns]};
    block_pair(src_row, base, &shuffle_[static_cast<std::size_t>(b) * 16], &x_weight_[2 * static_cast<std::size_t>(d)],
               out + d);
  }
  // Columns between the leading blocks and the tail pair (the leading blocks stop where a 16-byte
  // load from their first pixel would pass the row's end), then the tail pair.
  const int scalar_end = tail_blocks_ ? dst_width_ - 2 * kBlockColumns : dst_width_;
  for (; d < scalar_end; ++d) out[d] = horizontal(src_row, d);
  if (tail_blocks_ && d < dst_width_) {
    const int first = dst_width_ - 2 * kBlockColumns;
    block_pair(src_row, tail_base_, tail_shuffle_.data(), &x_weight_[2 * static_cast<std::size_t>(first)], out + first);
    d = dst_width_;
  }
#endif
  for (; d < dst_width_; ++d) out[d] = horizontal(src_row, d);
}

std::int16_t LinearResize::horizontal(const std::uint8_t* src_row, int d) const {
  const int x = x_offset_[d];
  const int right = std::min(x + 1, src_width_ - 1);  // weight 0 where clamped
  const int sum = src_row[x] * x_weight_[2 * d] + src_row[right] * x_weight_[2 * d + 1];
  return static_cast<std::int16_t>(sum >> 4);
}

void LinearResize::apply(const cv::Mat& src, cv::Mat& dst) {
  if (src.empty() || src.type() != CV_8UC1 || dst.empty() || dst.type() != CV_8UC1) {
    throw std::invalid_argument("LinearResize: expected a non-empty 8-bit grey source and destination");
  }
  if (dst.cols > src.cols || dst.rows > src.rows) {
    // Upscales are not needed by the pyramid and their clamped edges are not checked against OpenCV.
    cv::Mat resized;
    cv::resize(src, resized, dst.size(), 0, 0, cv::INTER_LINEAR);
    resized.copyTo(dst);
    return;
  }
  if (src.cols != src_width_ || dst.cols != dst_width_) plan(src.cols, dst.cols);
  for (auto& row : rows_) row.resize(static_cast<std::size_t>(dst.cols));
  row_y_[0] = row_y_[1] = -1;  // a new source image

  const double scale_y = 1.0 / (static_cast<double>(dst.rows) / src.rows);
  for (int y = 0; y < dst.rows; ++y) {
    const SourceCoordinate c = source_coordinate(y, scale_y);
    const std::int16_t b0 = weight(1.f - c.fraction);
    const std::int16_t b1 = weight(c.fraction);
    const int y0 = std::clamp(c.index, 0, src.rows - 1);
    const int y1 = std::clamp(c.index + 1, 0, src.rows - 1);
    // Each source row is resized horizontally once: keep the two last ones.
    int k0 = row_y_[0] == y0 ? 0 : row_y_[1] == y0 ? 1 : -1;
    if (k0 < 0) {
      k0 = row_y_[0] == y1 ? 1 : 0;
      resize_row(src.ptr<std::uint8_t>(y0), rows_[k0].data());
      row_y_[k0] = y0;
    }
    const int k1 = y1 == y0 ? k0 : 1 - k0;
    if (row_y_[k1] != y1) {
      resize_row(src.ptr<std::uint8_t>(y1), rows_[k1].data());
      row_y_[k1] = y1;
    }
    const std::int16_t* h0 = rows_[k0].data();
    const std::int16_t* h1 = rows_[k1].data();
    std::uint8_t* out = dst.ptr<std::uint8_t>(y);
    int x = 0;
#if defined(__AVX2__)
    const __m256i w0 = _mm256_set1_epi16(b0);
    const __m256i w1 = _mm256_set1_epi16(b1);
    const __m256i two = _mm256_set1_epi16(2);
    const auto half = [&](int at) {
      const __m256i r0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(h0 + at));
      const __m256i r1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(h1 + at));
      const __m256i sum = _mm256_add_epi16(_mm256_mulhi_epi16(r0, w0), _mm256_mulhi_epi16(r1, w1));
      return _mm256_srai_epi16(_mm256_add_epi16(sum, two), 2);
    };
    const auto block = [&](int at) {
      const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi16(half(at), half(at + 16)), 0xD8);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + at), packed);
    };
    for (; x + 32 <= dst.cols; x += 32) block(x);
    if (x < dst.cols && dst.cols >= 32) {
      // The rest as one more block ending at the last column (a few columns written twice, the same).
      block(dst.cols - 32);
      x = dst.cols;
    }
#endif
    for (; x < dst.cols; ++x) out[x] = vertical(h0[x], h1[x], b0, b1);
  }
}

}  // namespace heslam

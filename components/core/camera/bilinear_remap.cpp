// Exact fixed-point bilinear remapping (cv::remap INTER_LINEAR, BORDER_CONSTANT 0) for 8-bit images.
#include "components/core/camera/bilinear_remap.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace heslam {
namespace {

// Output pixels per vector block (eight 32-bit lanes).
constexpr int kBlock = 8;
// The map's fraction: fy * kTab + fx, both in 1/kTab px (cv::INTER_TAB_SIZE).
constexpr int kTab = 32;
constexpr int kFracMask = kTab * kTab - 1;
// Weights sum to kTab^2 = 2^10; adding half of it rounds to nearest as cv::remap's 2^14 of 2^15.
constexpr int kWeightBits = 10;
constexpr int kRound = 1 << (kWeightBits - 1);

// The scalar formula for one output pixel; taps outside the source are 0.
std::uint8_t remap_pixel(const cv::Mat& src, int sx, int sy, int frac) {
  const int fx = frac & (kTab - 1);
  const int fy = (frac & kFracMask) / kTab;
  const auto tap = [&](int x, int y) -> int {
    if (x < 0 || y < 0 || x >= src.cols || y >= src.rows) return 0;
    return src.ptr<std::uint8_t>(y)[x];
  };
  const int sum = (kTab - fx) * (kTab - fy) * tap(sx, sy) + fx * (kTab - fy) * tap(sx + 1, sy) +
                  (kTab - fx) * fy * tap(sx, sy + 1) + fx * fy * tap(sx + 1, sy + 1);
  return static_cast<std::uint8_t>((sum + kRound) >> kWeightBits);
}

}  // namespace

BilinearRemap::BilinearRemap(const cv::Mat& map_xy, const cv::Mat& map_frac, cv::Size src_size)
    : map_xy_(map_xy), map_frac_(map_frac), src_size_(src_size) {
  if (map_xy.type() != CV_16SC2 || map_frac.type() != CV_16UC1 || map_xy.size() != map_frac.size() ||
      map_xy.empty() || src_size.width < 2 || src_size.height < 2) {
    throw std::invalid_argument("BilinearRemap: expected CV_16SC2 and CV_16UC1 maps of one size and a source of at least 2x2");
  }
  blocks_per_row_ = (map_xy.cols + kBlock - 1) / kBlock;
  block_inside_.assign(static_cast<std::size_t>(blocks_per_row_) * static_cast<std::size_t>(map_xy.rows), 0);
  // A block takes the vector path when every pixel's 2x2 neighbourhood is inside the source and the
  // two 4-byte reads per pixel (rows sy and sy + 1 from sx) end inside a continuous source buffer.
  const std::int64_t buffer_bytes = static_cast<std::int64_t>(src_size.width) * src_size.height;
  for (int y = 0; y < map_xy.rows; ++y) {
    const std::int16_t* xy = map_xy.ptr<std::int16_t>(y);
    for (int block = 0; block < blocks_per_row_; ++block) {
      const int x0 = block * kBlock;
      if (x0 + kBlock > map_xy.cols) continue;
      bool inside = true;
      for (int x = x0; x < x0 + kBlock && inside; ++x) {
        const int sx = xy[2 * x];
        const int sy = xy[2 * x + 1];
        const std::int64_t last_byte = static_cast<std::int64_t>(sy + 1) * src_size.width + sx + 3;
        inside = sx >= 0 && sy >= 0 && sx <= src_size.width - 2 && sy <= src_size.height - 2 && last_byte < buffer_bytes;
      }
      block_inside_[static_cast<std::size_t>(y) * static_cast<std::size_t>(blocks_per_row_) + static_cast<std::size_t>(block)] =
          inside ? 1 : 0;
    }
  }
}

void BilinearRemap::apply(const cv::Mat& src, cv::Mat& dst) const {
  if (src.type() != CV_8UC1 || src.size() != src_size_) {
    throw std::invalid_argument("BilinearRemap: source is " + std::to_string(src.cols) + "x" + std::to_string(src.rows) +
                                " type " + std::to_string(src.type()) + ", expected " + std::to_string(src_size_.width) +
                                "x" + std::to_string(src_size_.height) + " 8-bit grey");
  }
  if (empty()) throw std::invalid_argument("BilinearRemap: no maps");
  dst.create(map_xy_.size(), CV_8UC1);
  // The block table assumes rows packed one after the other (the gathers' bounds).
  const bool vector_ok = src.isContinuous();
  for (int y = 0; y < map_xy_.rows; ++y) {
    const std::int16_t* xy = map_xy_.ptr<std::int16_t>(y);
    const std::uint16_t* frac = map_frac_.ptr<std::uint16_t>(y);
    std::uint8_t* out = dst.ptr<std::uint8_t>(y);
    const unsigned char* inside = block_inside_.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(blocks_per_row_);
    for (int block = 0; block < blocks_per_row_; ++block) {
      const int x0 = block * kBlock;
#if defined(__AVX2__)
      if (vector_ok && inside[block]) {
        const auto* base = reinterpret_cast<const int*>(src.data);
        const auto* base_below = reinterpret_cast<const int*>(src.data + src.cols);
        // Lane k: sx + sy * width (the int16 pair (sx, sy) times (1, width)).
        const __m256i pair = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(xy + 2 * x0));
        const __m256i offset = _mm256_madd_epi16(pair, _mm256_set1_epi32((src.cols << 16) | 1));
        const __m256i row0 = _mm256_i32gather_epi32(base, offset, 1);
        const __m256i row1 = _mm256_i32gather_epi32(base_below, offset, 1);
        // Bytes 0 and 1 of each lane as an int16 pair: (S00, S01) and (S10, S11).
        const __m256i spread = _mm256_setr_epi8(0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1,  //
                                                0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1);
        const __m256i top = _mm256_shuffle_epi8(row0, spread);
        const __m256i bottom = _mm256_shuffle_epi8(row1, spread);
        const __m256i f = _mm256_and_si256(
            _mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(frac + x0))), _mm256_set1_epi32(kFracMask));
        const __m256i tab = _mm256_set1_epi32(kTab);
        const __m256i fx = _mm256_and_si256(f, _mm256_set1_epi32(kTab - 1));
        const __m256i fy = _mm256_srli_epi32(f, 5);
        // (32 - fx, fx) as an int16 pair; (32 - fy) and fy in both halves.
        const __m256i wx = _mm256_or_si256(_mm256_sub_epi32(tab, fx), _mm256_slli_epi32(fx, 16));
        const __m256i wy0 = _mm256_sub_epi32(tab, fy);
        const __m256i w_top = _mm256_mullo_epi16(wx, _mm256_or_si256(wy0, _mm256_slli_epi32(wy0, 16)));
        const __m256i w_bottom = _mm256_mullo_epi16(wx, _mm256_or_si256(fy, _mm256_slli_epi32(fy, 16)));
        __m256i sum = _mm256_add_epi32(_mm256_madd_epi16(top, w_top), _mm256_madd_epi16(bottom, w_bottom));
        sum = _mm256_srli_epi32(_mm256_add_epi32(sum, _mm256_set1_epi32(kRound)), kWeightBits);
        const __m256i words = _mm256_packus_epi32(sum, sum);
        const __m256i bytes = _mm256_packus_epi16(words, words);
        const std::uint32_t first = static_cast<std::uint32_t>(_mm256_extract_epi32(bytes, 0));
        const std::uint32_t second = static_cast<std::uint32_t>(_mm256_extract_epi32(bytes, 4));
        std::memcpy(out + x0, &first, sizeof first);
        std::memcpy(out + x0 + 4, &second, sizeof second);
        continue;
      }
#else
      (void)vector_ok;
      (void)inside;
#endif
      const int x1 = std::min(x0 + kBlock, map_xy_.cols);
      for (int x = x0; x < x1; ++x) out[x] = remap_pixel(src, xy[2 * x], xy[2 * x + 1], frac[x]);
    }
  }
}

}  // namespace heslam

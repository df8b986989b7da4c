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

// How a block of output pixels is computed (BilinearRemap::block_mode_).
constexpr unsigned char kScalar = 0;
constexpr unsigned char kGathers = 1;
constexpr unsigned char kWindows = 2;
// Bytes of one source window (an SSE register): the pixels of half a block and their right neighbours.
constexpr int kWindow = 16;

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
  if (map_xy.type() != CV_16SC2 || map_frac.type() != CV_16UC1 || map_xy.size() != map_frac.size() || map_xy.empty() ||
      src_size.width < 2 || src_size.height < 2) {
    throw std::invalid_argument(
        "BilinearRemap: expected CV_16SC2 and CV_16UC1 maps of one size and a source of at least 2x2");
  }
  blocks_per_row_ = (map_xy.cols + kBlock - 1) / kBlock;
  const std::size_t blocks = static_cast<std::size_t>(blocks_per_row_) * static_cast<std::size_t>(map_xy.rows);
  block_mode_.assign(blocks, kScalar);
  block_window_.assign(2 * blocks, 0);
  // A block takes a vector path when every pixel's 2x2 neighbourhood is inside the source and the
  // reads (rows sy and sy + 1 from sx) end inside a continuous source buffer: 16-byte windows when
  // each half block's pixels lie within one (a rectification map moves ~1 px per output pixel), else
  // two 4-byte gathers per pixel.
  const std::int64_t width = src_size.width;
  const std::int64_t buffer_bytes = width * src_size.height;
  for (int y = 0; y < map_xy.rows; ++y) {
    const std::int16_t* xy = map_xy.ptr<std::int16_t>(y);
    for (int block = 0; block < blocks_per_row_; ++block) {
      const int x0 = block * kBlock;
      if (x0 + kBlock > map_xy.cols) continue;
      const std::size_t b =
          static_cast<std::size_t>(y) * static_cast<std::size_t>(blocks_per_row_) + static_cast<std::size_t>(block);
      bool inside = true;
      bool windows = true;
      for (int half = 0; half < 2; ++half) {
        std::int64_t lowest = buffer_bytes;
        std::int64_t highest = -1;
        for (int x = x0 + half * kBlock / 2; x < x0 + (half + 1) * kBlock / 2; ++x) {
          const int sx = xy[2 * x];
          const int sy = xy[2 * x + 1];
          const std::int64_t offset = sy * width + sx;
          inside = inside && sx >= 0 && sy >= 0 && sx <= src_size.width - 2 && sy <= src_size.height - 2 &&
                   offset + width + 3 < buffer_bytes;
          lowest = std::min(lowest, offset);
          highest = std::max(highest, offset);
        }
        windows = windows && highest + 1 - lowest < kWindow && lowest + width + kWindow <= buffer_bytes;
        block_window_[2 * b + static_cast<std::size_t>(half)] =
            static_cast<std::int32_t>(std::max<std::int64_t>(lowest, 0));
      }
      if (inside) block_mode_[b] = windows ? kWindows : kGathers;
    }
  }
}

void BilinearRemap::apply(const cv::Mat& src, cv::Mat& dst) const {
  if (src.type() != CV_8UC1 || src.size() != src_size_) {
    throw std::invalid_argument("BilinearRemap: source is " + std::to_string(src.cols) + "x" +
                                std::to_string(src.rows) + " type " + std::to_string(src.type()) + ", expected " +
                                std::to_string(src_size_.width) + "x" + std::to_string(src_size_.height) +
                                " 8-bit grey");
  }
  if (empty()) throw std::invalid_argument("BilinearRemap: no maps");
  dst.create(map_xy_.size(), CV_8UC1);
  // The block table assumes rows packed one after the other (the gathers' bounds).
  const bool vector_ok = src.isContinuous();
  for (int y = 0; y < map_xy_.rows; ++y) {
    const std::int16_t* xy = map_xy_.ptr<std::int16_t>(y);
    const std::uint16_t* frac = map_frac_.ptr<std::uint16_t>(y);
    std::uint8_t* out = dst.ptr<std::uint8_t>(y);
    const std::size_t row_blocks = static_cast<std::size_t>(y) * static_cast<std::size_t>(blocks_per_row_);
    const unsigned char* mode = block_mode_.data() + row_blocks;
    const std::int32_t* window = block_window_.data() + 2 * row_blocks;
    for (int block = 0; block < blocks_per_row_; ++block) {
      const int x0 = block * kBlock;
#if defined(__AVX2__)
      if (vector_ok && mode[block] != kScalar) {
        // Lane k: sx + sy * width (the int16 pair (sx, sy) times (1, width)).
        const __m256i pair = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(xy + 2 * x0));
        const __m256i offset = _mm256_madd_epi16(pair, _mm256_set1_epi32((src.cols << 16) | 1));
        // (S00, S01) and (S10, S11) of each lane as int16 pairs.
        __m256i top, bottom;
        if (mode[block] == kWindows) {
          // Each half block's 2x2 neighbourhoods lie in the 16 bytes from its window start, in both rows:
          // a byte shuffle picks (offset - start, offset - start + 1) per lane, zero-extended.
          const std::int32_t low = window[2 * block];
          const std::int32_t high = window[2 * block + 1];
          const __m256i start = _mm256_setr_epi32(low, low, low, low, high, high, high, high);
          const __m256i index = _mm256_sub_epi32(offset, start);
          const __m256i control = _mm256_or_si256(
              _mm256_add_epi32(_mm256_add_epi32(index, _mm256_slli_epi32(index, 16)), _mm256_set1_epi32(1 << 16)),
              _mm256_set1_epi32(static_cast<int>(0x80008000u)));
          const std::uint8_t* row0 = src.data;
          const std::uint8_t* row1 = src.data + src.cols;
          top = _mm256_shuffle_epi8(_mm256_loadu2_m128i(reinterpret_cast<const __m128i*>(row0 + high),
                                                        reinterpret_cast<const __m128i*>(row0 + low)),
                                    control);
          bottom = _mm256_shuffle_epi8(_mm256_loadu2_m128i(reinterpret_cast<const __m128i*>(row1 + high),
                                                           reinterpret_cast<const __m128i*>(row1 + low)),
                                       control);
        } else {
          const __m256i row0 = _mm256_i32gather_epi32(reinterpret_cast<const int*>(src.data), offset, 1);
          const __m256i row1 = _mm256_i32gather_epi32(reinterpret_cast<const int*>(src.data + src.cols), offset, 1);
          // Bytes 0 and 1 of each lane.
          const __m256i spread = _mm256_setr_epi8(0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1,  //
                                                  0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1);
          top = _mm256_shuffle_epi8(row0, spread);
          bottom = _mm256_shuffle_epi8(row1, spread);
        }
        const __m256i f =
            _mm256_and_si256(_mm256_cvtepu16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(frac + x0))),
                             _mm256_set1_epi32(kFracMask));
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
      (void)mode;
      (void)window;
#endif
      const int x1 = std::min(x0 + kBlock, map_xy_.cols);
      for (int x = x0; x < x1; ++x) out[x] = remap_pixel(src, xy[2 * x], xy[2 * x + 1], frac[x]);
    }
  }
}

}  // namespace heslam

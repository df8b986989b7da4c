// The descriptor blur, bit-exact with OpenCV's fixed-point cv::GaussianBlur: with AVX2 a horizontal
// then a vertical 7-tap pass over blocks of 32 pixels; otherwise (and for regions narrower than a
// block) a vertical then a horizontal pass, 16 or 8 pixels at a time (AVX2, SSE2; scalar elsewhere).
#include "components/core/feature/descriptor_blur.hpp"

#include <algorithm>
#include <cstddef>
#include <stdexcept>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace heslam {
namespace {

// OpenCV's fixed-point 7-tap kernel for sigma 2 (8 fractional bits, sums to 256), outermost first.
// Read from cv::GaussianBlur itself (the response to a line of 255s) and checked against it in
// tests/vision/descriptor_blur_test.cpp.
constexpr std::uint16_t kTap3 = 18;
constexpr std::uint16_t kTap2 = 34;
constexpr std::uint16_t kTap1 = 48;
constexpr std::uint16_t kTap0 = 56;
static_assert(2 * (kTap3 + kTap2 + kTap1) + kTap0 == 256, "the kernel must sum to 1 in 8-bit fixed point");

// All arithmetic is on 16-bit lanes. Every intermediate value below fits 16 bits unsigned (bounds in
// the comments of vertical() and horizontal()), so lane wrap-around never happens.
struct ScalarLanes {
  using V = std::uint32_t;
  static constexpr int kWidth = 1;
  static V load_u8(const std::uint8_t* p) { return *p; }
  static V load_u16(const std::uint16_t* p) { return *p; }
  static void store_u16(std::uint16_t* p, V v) { *p = static_cast<std::uint16_t>(v); }
  static void store_u8(std::uint8_t* p, V v) { *p = static_cast<std::uint8_t>(v); }
  static V add(V a, V b) { return a + b; }
  static V mul(V a, std::uint16_t k) { return a * k; }
  static V high_byte(V a) { return a >> 8; }
  static V low_byte(V a) { return a & 0xffu; }
  static V splat(std::uint16_t x) { return x; }
};

#if defined(__AVX2__)
struct SimdLanes {
  using V = __m256i;
  static constexpr int kWidth = 16;
  static V load_u8(const std::uint8_t* p) {
    return _mm256_cvtepu8_epi16(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
  }
  static V load_u16(const std::uint16_t* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); }
  static void store_u16(std::uint16_t* p, V v) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), v); }
  static void store_u8(std::uint8_t* p, V v) {
    // packus works within 128-bit halves: bytes 0-7 | 0-7 | 8-15 | 8-15; gather qwords 0 and 2.
    const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi16(v, v), 0x08);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(p), _mm256_castsi256_si128(packed));
  }
  static V add(V a, V b) { return _mm256_add_epi16(a, b); }
  static V mul(V a, std::uint16_t k) { return _mm256_mullo_epi16(a, _mm256_set1_epi16(static_cast<short>(k))); }
  static V high_byte(V a) { return _mm256_srli_epi16(a, 8); }
  static V low_byte(V a) { return _mm256_and_si256(a, _mm256_set1_epi16(0xff)); }
  static V splat(std::uint16_t x) { return _mm256_set1_epi16(static_cast<short>(x)); }
};
#elif defined(__SSE2__)
struct SimdLanes {
  using V = __m128i;
  static constexpr int kWidth = 8;
  static V load_u8(const std::uint8_t* p) {
    return _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)), _mm_setzero_si128());
  }
  static V load_u16(const std::uint16_t* p) { return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p)); }
  static void store_u16(std::uint16_t* p, V v) { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), v); }
  static void store_u8(std::uint8_t* p, V v) {
    _mm_storel_epi64(reinterpret_cast<__m128i*>(p), _mm_packus_epi16(v, v));
  }
  static V add(V a, V b) { return _mm_add_epi16(a, b); }
  static V mul(V a, std::uint16_t k) { return _mm_mullo_epi16(a, _mm_set1_epi16(static_cast<short>(k))); }
  static V high_byte(V a) { return _mm_srli_epi16(a, 8); }
  static V low_byte(V a) { return _mm_and_si128(a, _mm_set1_epi16(0xff)); }
  static V splat(std::uint16_t x) { return _mm_set1_epi16(static_cast<short>(x)); }
};
#else
using SimdLanes = ScalarLanes;
#endif

// Column sums of L::kWidth pixels from `centre` (row y): sum_j k_j p(y + j). At most 256 * 255.
template <class L>
[[gnu::always_inline]] inline void vertical(const std::uint8_t* centre, std::ptrdiff_t step, std::uint16_t* out) {
  using V = typename L::V;
  V sum = L::mul(L::add(L::load_u8(centre - 3 * step), L::load_u8(centre + 3 * step)), kTap3);
  sum = L::add(sum, L::mul(L::add(L::load_u8(centre - 2 * step), L::load_u8(centre + 2 * step)), kTap2));
  sum = L::add(sum, L::mul(L::add(L::load_u8(centre - step), L::load_u8(centre + step)), kTap1));
  sum = L::add(sum, L::mul(L::load_u8(centre), kTap0));
  L::store_u16(out, sum);
}

// sum_i k_i s(x + i) of one byte part of the column sums (each part <= 255, so the sum <= 256 * 255).
template <class L, class Part>
[[gnu::always_inline]] inline typename L::V weighted_part(const typename L::V (&s)[7], Part part) {
  typename L::V sum = L::mul(L::add(part(s[0]), part(s[6])), kTap3);
  sum = L::add(sum, L::mul(L::add(part(s[1]), part(s[5])), kTap2));
  sum = L::add(sum, L::mul(L::add(part(s[2]), part(s[4])), kTap1));
  return L::add(sum, L::mul(part(s[3]), kTap0));
}

// Output pixels of L::kWidth columns: (sum_i k_i s(x + i) + 2^15) >> 16 with s = 256 h + l split into
// bytes, the total = 256 A + B with A = sum k h and B = sum k l (both <= 65280). Since A is an
// integer, (256 A + B + 2^15) >> 16 = (A + (B >> 8) + 128) >> 8, and A + (B >> 8) <= total / 256
// <= 65280 keeps the sum inside 16 bits.
template <class L>
[[gnu::always_inline]] inline void horizontal(const std::uint16_t* centre, std::uint8_t* out) {
  typename L::V s[7];
  for (int i = 0; i < 7; ++i) s[i] = L::load_u16(centre + i - 3);
  const typename L::V high = weighted_part<L>(s, [](typename L::V v) { return L::high_byte(v); });
  const typename L::V low = weighted_part<L>(s, [](typename L::V v) { return L::low_byte(v); });
  L::store_u8(out, L::high_byte(L::add(L::add(high, L::high_byte(low)), L::splat(128))));
}

// Runs `block(x, lanes)` over [0, count) in SIMD blocks; the tail as one more block ending at the last
// element (recomputing a few, with the same result), or element by element when count < one block.
template <class Simd, class Scalar>
void for_blocks(int count, Simd simd, Scalar scalar) {
  constexpr int lanes = SimdLanes::kWidth;
  int x = 0;
  for (; x + lanes <= count; x += lanes) simd(x);
  if (x == count) return;
  if (count >= lanes) {
    simd(count - lanes);
  } else {
    for (; x < count; ++x) scalar(x);
  }
}

#if defined(__AVX2__)
// The AVX2 path: horizontal pass first, on bytes, then vertical, on 16-bit row sums, 32 pixels per
// block. OpenCV's kernel is twice k' = {9, 17, 24, 28, 24, 17, 9} (which sums to 128), so
//   (sum_ij k_i k_j p + 2^15) >> 16 = (S' + 2^13) >> 14,  S' = sum_ij k'_i k'_j p <= 128 * 128 * 255,
// and a row sum H = sum_i k'_i p <= 128 * 255 = 32640 fits a signed 16-bit lane: pmaddubsw makes
// the row sums from adjacent byte pairs (no widening of the pixels), pmaddwd the column sums in 32
// bits (exact, no high/low byte split).
constexpr int kBlockPx = 32;
constexpr int kRingRows = 2 * DescriptorBlur::kRadiusPx + 1;
constexpr std::int16_t kHalf3 = kTap3 / 2;  // 9
constexpr std::int16_t kHalf2 = kTap2 / 2;  // 17
constexpr std::int16_t kHalf1 = kTap1 / 2;  // 24
constexpr std::int16_t kHalf0 = kTap0 / 2;  // 28
static_assert(2 * (kHalf3 + kHalf2 + kHalf1) + kHalf0 == 128 && 2 * kHalf3 == kTap3 && 2 * kHalf2 == kTap2 &&
                  2 * kHalf1 == kTap1 && 2 * kHalf0 == kTap0,
              "the kernel must be twice a kernel summing to 128");
// Row sums are stored minus this bias, in [-16320, 16320], so the sum of two of them fits a signed
// 16-bit lane for pmaddwd. Column sum with biased rows: S' - 128 * bias, and the bias is chosen so
// that S' + 2^13 = that + 2^21: the result is (biased sum >> 14) + 128, i.e. an arithmetic shift,
// a signed byte pack and a flip of the byte's top bit, no 32-bit constant to add.
constexpr std::int16_t kRowBias = 16320;
static_assert(128 * kRowBias + (1 << 13) == 128 << 14, "the bias must turn the rounding into + 128 after the shift");
static_assert(2 * (128 * 255 - kRowBias) <= 32767 && -2 * kRowBias >= -32768,
              "pair sums of biased rows must fit 16 bits");

// Byte pairs (low, high) as one pmaddubsw weight vector.
__m256i byte_pair(int low, int high) { return _mm256_set1_epi16(static_cast<short>(low | (high << 8))); }
// 16-bit pairs (low, high) as one pmaddwd weight vector.
__m256i word_pair(int low, int high) { return _mm256_set1_epi32(low | (high << 16)); }

// Biased row sums of the 32 pixels p[0 .. 31] (reads p[-3] .. p[34]): the 16 even ones, then the 16
// odd ones, into `out` (32 lanes). pmaddubsw pairs bytes 2m and 2m + 1 of a load, so a load from
// p - 3 pairs the taps -3, -2 of pixel 2m, one from p - 2 those of pixel 2m + 1, and so on.
[[gnu::always_inline]] inline void row_sums(const std::uint8_t* p, std::int16_t* out) {
  const auto load = [p](int dx) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + dx)); };
  const __m256i w32 = byte_pair(kHalf3, kHalf2);  // taps -3, -2
  const __m256i w10 = byte_pair(kHalf1, kHalf0);  // taps -1, 0
  const __m256i w12 = byte_pair(kHalf1, kHalf2);  // taps +1, +2
  const __m256i bias = _mm256_set1_epi16(kRowBias);
  const __m256i last = load(3);  // tap +3: byte 2m for even pixels, 2m + 1 for odd ones
  const __m256i even = _mm256_add_epi16(
      _mm256_add_epi16(_mm256_maddubs_epi16(load(-3), w32), _mm256_maddubs_epi16(load(-1), w10)),
      _mm256_add_epi16(_mm256_maddubs_epi16(load(1), w12), _mm256_maddubs_epi16(last, byte_pair(kHalf3, 0))));
  const __m256i odd = _mm256_add_epi16(
      _mm256_add_epi16(_mm256_maddubs_epi16(load(-2), w32), _mm256_maddubs_epi16(load(0), w10)),
      _mm256_add_epi16(_mm256_maddubs_epi16(load(2), w12), _mm256_maddubs_epi16(last, byte_pair(0, kHalf3))));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), _mm256_sub_epi16(even, bias));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + 16), _mm256_sub_epi16(odd, bias));
}

// (biased column sum of 16 lanes >> 14) as 16 signed 16-bit lanes in [-128, 127], in lane order.
// rows[j] points at the lanes of row sums j - 3.
[[gnu::always_inline]] inline __m256i column_sums(const std::int16_t* const (&rows)[kRingRows], int offset) {
  const auto load = [&](int j) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(rows[j] + offset)); };
  const __m256i pair3 = _mm256_add_epi16(load(0), load(6));
  const __m256i pair2 = _mm256_add_epi16(load(1), load(5));
  const __m256i pair1 = _mm256_add_epi16(load(2), load(4));
  const __m256i centre = load(3);
  const __m256i w32 = word_pair(kHalf3, kHalf2);
  const __m256i w10 = word_pair(kHalf1, kHalf0);
  // unpacklo / unpackhi take lanes 0-3, 8-11 / 4-7, 12-15; packs_epi32 restores the order.
  const __m256i low = _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpacklo_epi16(pair3, pair2), w32),
                                       _mm256_madd_epi16(_mm256_unpacklo_epi16(pair1, centre), w10));
  const __m256i high = _mm256_add_epi32(_mm256_madd_epi16(_mm256_unpackhi_epi16(pair3, pair2), w32),
                                        _mm256_madd_epi16(_mm256_unpackhi_epi16(pair1, centre), w10));
  return _mm256_packs_epi32(_mm256_srai_epi32(low, 14), _mm256_srai_epi32(high, 14));
}

// The 32 output pixels of one block from its row sums (even lanes at 0, odd lanes at 16).
[[gnu::always_inline]] inline void block_output(const std::int16_t* const (&rows)[kRingRows], int offset,
                                                std::uint8_t* out) {
  const __m256i even = column_sums(rows, offset);
  const __m256i odd = column_sums(rows, offset + 16);
  // Per 128-bit half: even 0-7, odd 0-7 (then 8-15 in the upper half); interleave to pixel order.
  const __m256i packed = _mm256_packs_epi16(even, odd);
  const __m256i order = _mm256_setr_epi8(0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15,  //
                                         0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15);
  const __m256i pixels = _mm256_xor_si256(_mm256_shuffle_epi8(packed, order), _mm256_set1_epi8(-128));  // + 128
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), pixels);
}
#endif

}  // namespace

void DescriptorBlur::apply(const cv::Mat& src, const cv::Rect& region, cv::Mat& dst) {
  if (src.type() != CV_8UC1) throw std::invalid_argument("DescriptorBlur: expected an 8-bit grey image");
  const cv::Rect readable(kRadiusPx, kRadiusPx, src.cols - 2 * kRadiusPx, src.rows - 2 * kRadiusPx);
  if (region.width <= 0 || region.height <= 0 || (region & readable) != region) {
    throw std::invalid_argument("DescriptorBlur: the region and a 3-pixel ring around it must lie inside the image");
  }
  if (dst.data == src.data) throw std::invalid_argument("DescriptorBlur: dst must not share src's pixels");
  dst.create(src.size(), CV_8UC1);
#if defined(__AVX2__)
  if (region.width >= kBlockPx) {
    apply_blocks(src, region, dst);
    return;
  }
#endif
  const int sums_width = region.width + 2 * kRadiusPx;
  column_sums_.resize(static_cast<std::size_t>(sums_width));
  std::uint16_t* sums = column_sums_.data();
  const auto step = static_cast<std::ptrdiff_t>(src.step1());
  for (int y = region.y; y < region.y + region.height; ++y) {
    const std::uint8_t* first = src.ptr<std::uint8_t>(y) + region.x - kRadiusPx;
    for_blocks(
        sums_width, [&](int x) { vertical<SimdLanes>(first + x, step, sums + x); },
        [&](int x) { vertical<ScalarLanes>(first + x, step, sums + x); });
    std::uint8_t* out = dst.ptr<std::uint8_t>(y) + region.x;
    const std::uint16_t* centre = sums + kRadiusPx;
    for_blocks(
        region.width, [&](int x) { horizontal<SimdLanes>(centre + x, out + x); },
        [&](int x) { horizontal<ScalarLanes>(centre + x, out + x); });
  }
}

}  // namespace heslam

#if defined(__AVX2__)
namespace heslam {

void DescriptorBlur::apply_blocks(const cv::Mat& src, const cv::Rect& region, cv::Mat& dst) {
  // Blocks of 32 columns; the last one ends at the region's last column (a few columns computed
  // twice, with the same result).
  const int blocks = (region.width + kBlockPx - 1) / kBlockPx;
  const auto block_x = [&](int b) { return std::min(b * kBlockPx, region.width - kBlockPx); };
  const std::size_t row_lanes = static_cast<std::size_t>(blocks) * kBlockPx;
  ring_.resize(row_lanes * kRingRows);
  // Row sums of source row region.y + r go to ring slot (r + kRadiusPx) mod kRingRows.
  const auto slot = [&](int r) {
    return ring_.data() + static_cast<std::size_t>((r + kRadiusPx) % kRingRows) * row_lanes;
  };
  const auto fill = [&](int r) {
    const std::uint8_t* row = src.ptr<std::uint8_t>(region.y + r) + region.x;
    std::int16_t* out = slot(r);
    for (int b = 0; b < blocks; ++b) row_sums(row + block_x(b), out + static_cast<std::ptrdiff_t>(b) * kBlockPx);
  };
  for (int r = -kRadiusPx; r < kRadiusPx; ++r) fill(r);
  for (int y = 0; y < region.height; ++y) {
    fill(y + kRadiusPx);
    const std::int16_t* rows[kRingRows];
    for (int j = 0; j < kRingRows; ++j) rows[j] = slot(y + j - kRadiusPx);
    std::uint8_t* out = dst.ptr<std::uint8_t>(region.y + y) + region.x;
    for (int b = 0; b < blocks; ++b) block_output(rows, b * kBlockPx, out + block_x(b));
  }
}

}  // namespace heslam
#endif

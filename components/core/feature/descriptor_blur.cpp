// The descriptor blur: a vertical then a horizontal 7-tap integer pass, 16 or 8 pixels at a time
// (AVX2, SSE2; scalar elsewhere), bit-exact with OpenCV's fixed-point cv::GaussianBlur.
#include "components/core/feature/descriptor_blur.hpp"

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
  static void store_u8(std::uint8_t* p, V v) { _mm_storel_epi64(reinterpret_cast<__m128i*>(p), _mm_packus_epi16(v, v)); }
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

}  // namespace

void DescriptorBlur::apply(const cv::Mat& src, const cv::Rect& region, cv::Mat& dst) {
  if (src.type() != CV_8UC1) throw std::invalid_argument("DescriptorBlur: expected an 8-bit grey image");
  const cv::Rect readable(kRadiusPx, kRadiusPx, src.cols - 2 * kRadiusPx, src.rows - 2 * kRadiusPx);
  if (region.width <= 0 || region.height <= 0 || (region & readable) != region) {
    throw std::invalid_argument("DescriptorBlur: the region and a 3-pixel ring around it must lie inside the image");
  }
  if (dst.data == src.data) throw std::invalid_argument("DescriptorBlur: dst must not share src's pixels");
  dst.create(src.size(), CV_8UC1);
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

// Intensity-centroid orientation: scalar sums, or byte multiply-adds over whole patch rows.
#include "components/core/feature/intensity_centroid.hpp"

#include <cmath>
#include <numbers>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace heslam {

IntensityCentroid::IntensityCentroid() {
  for (int v = 0; v <= kRadiusPx; ++v) {
    const int half = static_cast<int>(std::lround(std::sqrt(static_cast<double>(kRadiusPx * kRadiusPx - v * v))));
    half_width_[static_cast<std::size_t>(v)] = half;
    for (int u = -half; u <= half; ++u) {
      u_weight_[static_cast<std::size_t>(v)][static_cast<std::size_t>(u + kRadiusPx)] = static_cast<std::int8_t>(u);
      v_weight_[static_cast<std::size_t>(v)][static_cast<std::size_t>(u + kRadiusPx)] = static_cast<std::int8_t>(v);
    }
  }
}

void IntensityCentroid::moments(const std::uint8_t* center, std::ptrdiff_t step, int& m10, int& m01) const {
#if defined(__AVX2__)
  // Row pair +-v: pmaddubsw multiplies the 32 pixels of a row (unsigned bytes) by the byte weights and
  // adds neighbouring products into 16-bit lanes (|pair| <= 2 * 15 * 255 = 7650, no saturation); the
  // m10 terms of both rows added (<= 15300) and the m01 terms subtracted (>= -15300) stay in 16 bits,
  // and pmaddwd with ones widens them into the 32-bit sums (exact).
  static_assert(2 * 2 * kRadiusPx * 255 <= 32767, "a row pair's 16-bit sums must not overflow");
  const auto load = [](const std::uint8_t* p) { return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p)); };
  const auto weights = [](const std::array<std::int8_t, kRowBytes>& w) {
    return _mm256_load_si256(reinterpret_cast<const __m256i*>(w.data()));
  };
  const __m256i ones = _mm256_set1_epi16(1);
  __m256i acc10 = _mm256_madd_epi16(_mm256_maddubs_epi16(load(center - kRadiusPx), weights(u_weight_[0])), ones);
  __m256i acc01 = _mm256_setzero_si256();
  for (int v = 1; v <= kRadiusPx; ++v) {
    const __m256i below = load(center + v * step - kRadiusPx);
    const __m256i above = load(center - v * step - kRadiusPx);
    const __m256i u = weights(u_weight_[static_cast<std::size_t>(v)]);
    const __m256i w = weights(v_weight_[static_cast<std::size_t>(v)]);
    const __m256i sum10 = _mm256_add_epi16(_mm256_maddubs_epi16(below, u), _mm256_maddubs_epi16(above, u));
    const __m256i sum01 = _mm256_sub_epi16(_mm256_maddubs_epi16(below, w), _mm256_maddubs_epi16(above, w));
    acc10 = _mm256_add_epi32(acc10, _mm256_madd_epi16(sum10, ones));
    acc01 = _mm256_add_epi32(acc01, _mm256_madd_epi16(sum01, ones));
  }
  auto sum_lanes = [](__m256i x) {
    __m128i s = _mm_add_epi32(_mm256_castsi256_si128(x), _mm256_extracti128_si256(x, 1));
    s = _mm_add_epi32(s, _mm_shuffle_epi32(s, 0x4e));
    s = _mm_add_epi32(s, _mm_shuffle_epi32(s, 0xb1));
    return _mm_cvtsi128_si32(s);
  };
  m10 = sum_lanes(acc10);
  m01 = sum_lanes(acc01);
#else
  m10 = 0;
  m01 = 0;
  for (int u = -kRadiusPx; u <= kRadiusPx; ++u) m10 += u * center[u];
  for (int v = 1; v <= kRadiusPx; ++v) {
    const int half = half_width_[static_cast<std::size_t>(v)];
    const std::uint8_t* below = center + v * step;
    const std::uint8_t* above = center - v * step;
    int sum_v = 0;
    for (int u = -half; u <= half; ++u) {
      const int b = below[u];
      const int a = above[u];
      sum_v += b - a;
      m10 += u * (b + a);
    }
    m01 += v * sum_v;
  }
#endif
}

float IntensityCentroid::angle_deg(const std::uint8_t* center, std::ptrdiff_t step) const {
  int m10 = 0;
  int m01 = 0;
  moments(center, step, m10, m01);
  float angle =
      static_cast<float>(std::atan2(static_cast<double>(m01), static_cast<double>(m10)) * (180.0 / std::numbers::pi));
  if (angle < 0.f) angle += 360.f;
  if (angle >= 360.f) angle -= 360.f;
  return angle;
}

}  // namespace heslam

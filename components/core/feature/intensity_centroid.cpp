// Intensity-centroid orientation: scalar sums, or 16-bit multiply-adds over whole patch rows.
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
      u_weight_[static_cast<std::size_t>(v)][static_cast<std::size_t>(u + kRadiusPx)] = static_cast<std::int16_t>(u);
      v_weight_[static_cast<std::size_t>(v)][static_cast<std::size_t>(u + kRadiusPx)] = static_cast<std::int16_t>(v);
    }
  }
}

void IntensityCentroid::moments(const std::uint8_t* center, std::ptrdiff_t step, int& m10, int& m01) const {
#if defined(__AVX2__)
  // Row pair +-v: m10 += sum u (below + above), m01 += sum v (below - above), as 16-bit lanes
  // (sums <= 510, differences >= -255) multiplied and added pairwise into 32-bit lanes (exact).
  auto load = [](const std::uint8_t* p, __m256i& low, __m256i& high) {
    const __m256i bytes = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
    low = _mm256_cvtepu8_epi16(_mm256_castsi256_si128(bytes));
    high = _mm256_cvtepu8_epi16(_mm256_extracti128_si256(bytes, 1));
  };
  auto weights = [](const std::array<std::int16_t, kRowBytes>& w, __m256i& low, __m256i& high) {
    low = _mm256_load_si256(reinterpret_cast<const __m256i*>(w.data()));
    high = _mm256_load_si256(reinterpret_cast<const __m256i*>(w.data() + 16));
  };
  __m256i c_low, c_high, u_low, u_high;
  load(center - kRadiusPx, c_low, c_high);
  weights(u_weight_[0], u_low, u_high);
  __m256i acc10 = _mm256_add_epi32(_mm256_madd_epi16(c_low, u_low), _mm256_madd_epi16(c_high, u_high));
  __m256i acc01 = _mm256_setzero_si256();
  for (int v = 1; v <= kRadiusPx; ++v) {
    __m256i b_low, b_high, a_low, a_high, v_low, v_high;
    load(center + v * step - kRadiusPx, b_low, b_high);
    load(center - v * step - kRadiusPx, a_low, a_high);
    weights(u_weight_[static_cast<std::size_t>(v)], u_low, u_high);
    weights(v_weight_[static_cast<std::size_t>(v)], v_low, v_high);
    acc10 = _mm256_add_epi32(acc10, _mm256_madd_epi16(_mm256_add_epi16(b_low, a_low), u_low));
    acc10 = _mm256_add_epi32(acc10, _mm256_madd_epi16(_mm256_add_epi16(b_high, a_high), u_high));
    acc01 = _mm256_add_epi32(acc01, _mm256_madd_epi16(_mm256_sub_epi16(b_low, a_low), v_low));
    acc01 = _mm256_add_epi32(acc01, _mm256_madd_epi16(_mm256_sub_epi16(b_high, a_high), v_high));
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
  float angle = static_cast<float>(std::atan2(static_cast<double>(m01), static_cast<double>(m10)) *
                                   (180.0 / std::numbers::pi));
  if (angle < 0.f) angle += 360.f;
  if (angle >= 360.f) angle -= 360.f;
  return angle;
}

}  // namespace heslam

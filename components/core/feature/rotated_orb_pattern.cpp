// Rotating the rBRIEF pattern: 2 x 256 points per keypoint, the largest part of a descriptor's cost
// after the blur when done one point at a time.
#include "components/core/feature/rotated_orb_pattern.hpp"

#include <cmath>
#include <cstddef>

#include <opencv2/core.hpp>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

namespace heslam {
namespace {

// The pattern's coordinates as floats, one array per coordinate (8 tests per vector load).
struct PatternCoordinates {
  std::array<float, kOrbPattern.size()> x1, y1, x2, y2;
};

constexpr PatternCoordinates pattern_coordinates() {
  PatternCoordinates p{};
  for (std::size_t t = 0; t < kOrbPattern.size(); ++t) {
    p.x1[t] = kOrbPattern[t][0];
    p.y1[t] = kOrbPattern[t][1];
    p.x2[t] = kOrbPattern[t][2];
    p.y2[t] = kOrbPattern[t][3];
  }
  return p;
}

constexpr PatternCoordinates kPattern = pattern_coordinates();

int rotated_offset(float x, float y, float c, float s, int step) {
#if defined(__FMA__)
  return cvRound(std::fma(x, s, y * c)) * step + cvRound(std::fma(x, c, -(y * s)));
#else
  return cvRound(x * s + y * c) * step + cvRound(x * c - y * s);
#endif
}

}  // namespace

void rotate_orb_pattern(float c, float s, int step, RotatedOrbPattern& out) {
  std::size_t t = 0;
#if defined(__AVX2__) && defined(__FMA__)
  const __m256 vc = _mm256_set1_ps(c);
  const __m256 vs = _mm256_set1_ps(s);
  const __m256i vstep = _mm256_set1_epi32(step);
  auto offsets = [&](const float* xs, const float* ys) {
    const __m256 x = _mm256_loadu_ps(xs);
    const __m256 y = _mm256_loadu_ps(ys);
    const __m256i row = _mm256_cvtps_epi32(_mm256_fmadd_ps(x, vs, _mm256_mul_ps(y, vc)));
    const __m256i column = _mm256_cvtps_epi32(_mm256_fmsub_ps(x, vc, _mm256_mul_ps(y, vs)));
    return _mm256_add_epi32(_mm256_mullo_epi32(row, vstep), column);
  };
  for (; t + 8 <= kOrbPattern.size(); t += 8) {
    _mm256_store_si256(reinterpret_cast<__m256i*>(&out.first[t]), offsets(&kPattern.x1[t], &kPattern.y1[t]));
    _mm256_store_si256(reinterpret_cast<__m256i*>(&out.second[t]), offsets(&kPattern.x2[t], &kPattern.y2[t]));
  }
#endif
  for (; t < kOrbPattern.size(); ++t) {
    out.first[t] = rotated_offset(kPattern.x1[t], kPattern.y1[t], c, s, step);
    out.second[t] = rotated_offset(kPattern.x2[t], kPattern.y2[t], c, s, step);
  }
}

}  // namespace heslam

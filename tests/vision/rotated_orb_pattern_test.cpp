// rotate_orb_pattern gives, for every angle, the offsets of the scalar formula ORB-SLAM2 and OpenCV
// use, with the first product of each sum fused where the CPU has FMA (as GCC compiled the
// extractor's formula before): the SIMD path must not change a single descriptor bit.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "components/core/feature/rotated_orb_pattern.hpp"

namespace heslam {
namespace {

int reference_offset(float x, float y, float c, float s, int step) {
#if defined(__FMA__)
  return cvRound(std::fma(x, s, y * c)) * step + cvRound(std::fma(x, c, -(y * s)));
#else
  // Kept from being contracted into FMAs by the compiler: volatile products.
  const volatile float xs = x * s, yc = y * c, xc = x * c, ys = y * s;
  return cvRound(xs + yc) * step + cvRound(xc - ys);
#endif
}

TEST(RotatedOrbPattern, EqualsTheScalarFormulaForEveryAngle) {
  constexpr int kStep = 790;  // a padded EuRoC level-0 row
  RotatedOrbPattern ours;
  int compared = 0;
  // 0.01 degree steps plus the exact multiples of 45 degrees (ties in the rounding).
  for (int centi_deg = 0; centi_deg < 36000; ++centi_deg) {
    const float radians = static_cast<float>(centi_deg) * 0.01f * static_cast<float>(std::numbers::pi / 180.0);
    const float c = std::cos(radians);
    const float s = std::sin(radians);
    rotate_orb_pattern(c, s, kStep, ours);
    for (std::size_t t = 0; t < kOrbPattern.size(); ++t) {
      const auto& q = kOrbPattern[t];
      const int first = reference_offset(q[0], q[1], c, s, kStep);
      const int second = reference_offset(q[2], q[3], c, s, kStep);
      ASSERT_EQ(ours.first[t], first) << "test " << t << " at " << centi_deg * 0.01 << " deg";
      ASSERT_EQ(ours.second[t], second) << "test " << t << " at " << centi_deg * 0.01 << " deg";
      ++compared;
    }
  }
  EXPECT_EQ(compared, 36000 * 256);
  // Angle 0: the pattern itself.
  rotate_orb_pattern(1.f, 0.f, kStep, ours);
  EXPECT_EQ(ours.first[0], kOrbPattern[0][1] * kStep + kOrbPattern[0][0]);
}

}  // namespace
}  // namespace heslam

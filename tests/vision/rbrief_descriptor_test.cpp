// rbrief_descriptor (SIMD sampling) gives the bits of the one-test-at-a-time reference for any angle
// and image, ties included (equal pixels give 0), and both follow the definition on a known image.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "components/core/feature/rbrief_descriptor.hpp"

namespace heslam {
namespace {

constexpr int kSide = 64;  // image side: the rotated pattern (radius < 19) around the centre fits
constexpr int kCentre = kSide / 2;

bool bit(const Descriptor& d, std::size_t t) { return ((d[t / 8] >> (t % 8)) & 1u) != 0; }

TEST(OrbDescriptor, SimdSamplingEqualsTheScalarTests) {
  std::mt19937 rng(31);
  std::vector<std::uint8_t> image(kSide * kSide);
  RotatedOrbPattern offsets;
  for (int trial = 0; trial < 500; ++trial) {
    // Full-range noise, or only 4 grey values (many equal pairs).
    const int levels = trial % 2 == 0 ? 256 : 4;
    for (std::uint8_t& p : image) p = static_cast<std::uint8_t>(rng() % levels * (255 / (levels - 1)));
    const float radians = static_cast<float>(rng() % 36000) * 0.01f * static_cast<float>(std::numbers::pi / 180.0);
    rotate_orb_pattern(std::cos(radians), std::sin(radians), kSide, offsets);
    const std::uint8_t* center = image.data() + kCentre * kSide + kCentre;
    ASSERT_EQ(rbrief_descriptor(center, offsets), rbrief_descriptor_scalar(center, offsets)) << "trial " << trial;
  }
}

TEST(OrbDescriptor, BitIsSetWhenTheFirstPointIsDarker) {
  // Grey value = x + 2 y (distinct along both axes): at angle 0 test t compares pattern points
  // (x1, y1) and (x2, y2) directly.
  std::vector<std::uint8_t> image(kSide * kSide);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x)
      image[static_cast<std::size_t>(y * kSide + x)] = static_cast<std::uint8_t>(x + 2 * y);
  }
  RotatedOrbPattern offsets;
  rotate_orb_pattern(1.f, 0.f, kSide, offsets);
  const std::uint8_t* center = image.data() + kCentre * kSide + kCentre;
  const Descriptor simd = rbrief_descriptor(center, offsets);
  const Descriptor scalar = rbrief_descriptor_scalar(center, offsets);
  int set = 0;
  for (std::size_t t = 0; t < kOrbPattern.size(); ++t) {
    const auto& q = kOrbPattern[t];
    const bool darker = q[0] + 2 * q[1] < q[2] + 2 * q[3];
    ASSERT_EQ(bit(simd, t), darker) << "test " << t;
    ASSERT_EQ(bit(scalar, t), darker) << "test " << t;
    set += darker ? 1 : 0;
  }
  EXPECT_GT(set, 0);
  EXPECT_LT(set, 256);
}

}  // namespace
}  // namespace heslam

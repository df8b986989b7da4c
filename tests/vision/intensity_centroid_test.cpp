// IntensityCentroid gives exactly the moments of the scalar sums over the circular patch (ORB's
// formula) on random, saturated and real image patches, and the angle of a known gradient.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "components/core/feature/intensity_centroid.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

constexpr int kRadius = IntensityCentroid::kRadiusPx;

void reference_moments(const cv::Mat& image, int x, int y, int& m10, int& m01) {
  m10 = 0;
  m01 = 0;
  for (int v = -kRadius; v <= kRadius; ++v) {
    const int half = static_cast<int>(std::lround(std::sqrt(static_cast<double>(kRadius * kRadius - v * v))));
    for (int u = -half; u <= half; ++u) {
      const int value = image.at<std::uint8_t>(y + v, x + u);
      m10 += u * value;
      m01 += v * value;
    }
  }
}

void expect_reference_moments(const cv::Mat& image, int points, std::uint32_t seed) {
  const IntensityCentroid centroid;
  std::mt19937 rng(seed);
  for (int i = 0; i < points; ++i) {
    const int x = kRadius + static_cast<int>(rng() % static_cast<unsigned>(image.cols - 2 * kRadius - 1));
    const int y = kRadius + static_cast<int>(rng() % static_cast<unsigned>(image.rows - 2 * kRadius));
    int m10 = 0, m01 = 0, r10 = 0, r01 = 0;
    centroid.moments(image.ptr<std::uint8_t>(y) + x, static_cast<std::ptrdiff_t>(image.step1()), m10, m01);
    reference_moments(image, x, y, r10, r01);
    ASSERT_EQ(m10, r10) << "at " << x << ", " << y;
    ASSERT_EQ(m01, r01) << "at " << x << ", " << y;
  }
}

TEST(IntensityCentroid, EqualsTheScalarMomentsOnRandomAndSaturatedPatches) {
  std::mt19937 rng(3);
  cv::Mat noise(120, 150, CV_8UC1);
  for (int y = 0; y < noise.rows; ++y) {
    for (int x = 0; x < noise.cols; ++x) noise.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(rng() & 0xff);
  }
  expect_reference_moments(noise, 2000, 5);
  const cv::Mat binary = noise > 127;  // 0 and 255 only: the largest sums
  expect_reference_moments(binary, 2000, 6);
}

TEST(IntensityCentroid, EqualsTheScalarMomentsOnAEurocImage) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  const auto pairs = test::load_euroc_pairs({0}, nullptr);
  expect_reference_moments(pairs.at(0).left, 5000, 7);
}

TEST(IntensityCentroid, AngleOfAGradientPointsToTheBrightSide) {
  cv::Mat image(64, 64, CV_8UC1);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x)
      image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(2 * y);  // brighter downwards
  }
  const IntensityCentroid centroid;
  EXPECT_NEAR(centroid.angle_deg(image.ptr<std::uint8_t>(32) + 32, static_cast<std::ptrdiff_t>(image.step1())), 90.f,
              1e-4f);
  EXPECT_EQ(centroid.half_width(0), 15);
  EXPECT_EQ(centroid.half_width(15), 0);
}

}  // namespace
}  // namespace heslam

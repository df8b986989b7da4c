// DescriptorBlur gives exactly cv::GaussianBlur(7x7, sigma 2) on the pixels it blurs: random and
// saturated images of odd sizes (SIMD tails, regions narrower than a vector), a real EuRoC image, and
// leaves the pixels outside its region alone; every region width and alignment.
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "components/core/feature/descriptor_blur.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

cv::Mat opencv_blur(const cv::Mat& image) {
  cv::Mat blurred;
  cv::GaussianBlur(image, blurred, cv::Size(7, 7), 2.0, 2.0, cv::BORDER_REFLECT_101);
  return blurred;
}

// Number of pixels of `region` where ours and OpenCV's differ.
int differing_pixels(const cv::Mat& image, const cv::Rect& region) {
  DescriptorBlur blur;
  cv::Mat ours;
  blur.apply(image, region, ours);
  return cv::countNonZero(ours(region) != opencv_blur(image)(region));
}

TEST(DescriptorBlur, EqualsOpenCvOnRandomImagesAndRegions) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> grey(0, 255);
  for (int trial = 0; trial < 200; ++trial) {
    const int width = 7 + static_cast<int>(rng() % 120);
    const int height = 7 + static_cast<int>(rng() % 40);
    cv::Mat image(height, width, CV_8UC1);
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        // Every third image only 0 and 255: the largest sums.
        const int value = grey(rng);
        image.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(trial % 3 == 0 ? (value > 127 ? 255 : 0) : value);
      }
    }
    const int r = DescriptorBlur::kRadiusPx;
    const int x = r + static_cast<int>(rng() % static_cast<unsigned>(width - 2 * r));
    const int y = r + static_cast<int>(rng() % static_cast<unsigned>(height - 2 * r));
    const int w = 1 + static_cast<int>(rng() % static_cast<unsigned>(width - r - x));
    const int h = 1 + static_cast<int>(rng() % static_cast<unsigned>(height - r - y));
    const cv::Rect region = trial % 2 == 0 ? cv::Rect(x, y, w, h) : cv::Rect(r, r, width - 2 * r, height - 2 * r);
    ASSERT_EQ(differing_pixels(image, region), 0)
        << "trial " << trial << ", image " << width << "x" << height << ", region " << region;
  }
}

TEST(DescriptorBlur, EqualsOpenCvOnAEurocImage) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  const auto pairs = test::load_euroc_pairs({0}, nullptr);
  const cv::Mat& image = pairs.at(0).left;
  const int r = DescriptorBlur::kRadiusPx;
  EXPECT_EQ(differing_pixels(image, cv::Rect(r, r, image.cols - 2 * r, image.rows - 2 * r)), 0);
}

TEST(DescriptorBlur, WritesOnlyItsRegionAndRejectsRegionsWithoutRing) {
  cv::Mat image(40, 60, CV_8UC1, cv::Scalar(200));
  cv::Mat out(40, 60, CV_8UC1, cv::Scalar(7));
  DescriptorBlur blur;
  const cv::Rect region(10, 5, 20, 9);
  blur.apply(image, region, out);
  EXPECT_EQ(cv::countNonZero(out(region) != 200), 0);  // a flat image stays flat
  EXPECT_EQ(cv::countNonZero(out != 7), region.area());
  EXPECT_THROW(blur.apply(image, cv::Rect(2, 5, 10, 10), out), std::invalid_argument);
  EXPECT_THROW(blur.apply(image, cv::Rect(10, 30, 10, 8), out), std::invalid_argument);
  EXPECT_THROW(blur.apply(image, region, image), std::invalid_argument);
}

// Every region width from 1 to 150 (the SIMD blocks of 32 columns, the last one overlapping, and
// the narrow regions' path) at every offset modulo 8, on noise and on the largest sums (only 0 and
// 255, and a flat 255 image).
TEST(DescriptorBlur, EqualsOpenCvForEveryRegionWidthAndOffset) {
  std::mt19937 rng(23);
  std::uniform_int_distribution<int> grey(0, 255);
  cv::Mat noise(17, 170, CV_8UC1);
  for (int y = 0; y < noise.rows; ++y) {
    for (int x = 0; x < noise.cols; ++x) noise.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(grey(rng));
  }
  const cv::Mat flat(noise.size(), CV_8UC1, cv::Scalar(255));
  const cv::Mat binary = noise > 127;
  const int r = DescriptorBlur::kRadiusPx;
  for (const cv::Mat& image : {noise, binary, flat}) {
    for (int width = 1; width <= 150; ++width) {
      for (int x = r; x < r + 8; ++x) {
        const cv::Rect region(x, r + 1, width, image.rows - 2 * r - 2);
        ASSERT_EQ(differing_pixels(image, region), 0) << "region " << region;
      }
    }
  }
}

}  // namespace
}  // namespace heslam

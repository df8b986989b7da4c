// LinearResize writes exactly cv::resize(INTER_LINEAR)'s pixels: the ORB pyramid chains (EuRoC 752x480
// and KITTI 1241x376 sizes, scale 1.2) of a real texture, noise and a two-valued image, other
// downscale ratios, every source width's last columns, views into larger buffers (nothing written
// outside), repeated calls reusing the plan.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "components/core/feature/linear_resize.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

cv::Mat noise_image(int width, int height, unsigned seed, bool two_valued) {
  std::mt19937 rng(seed);
  cv::Mat image(height, width, CV_8UC1);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const auto v = static_cast<std::uint8_t>(rng());
      image.at<std::uint8_t>(y, x) = two_valued ? (v & 1 ? 255 : 0) : v;
    }
  }
  return image;
}

// Resizes into the middle of a larger buffer filled with a marker and compares with cv::resize.
void expect_same_as_opencv(LinearResize& resize, const cv::Mat& src, cv::Size size) {
  constexpr int kMargin = 7;
  constexpr std::uint8_t kMarker = 77;
  cv::Mat buffer(size.height + 2 * kMargin, size.width + 2 * kMargin, CV_8UC1, cv::Scalar(kMarker));
  cv::Mat ours = buffer(cv::Rect(kMargin, kMargin, size.width, size.height));
  resize.apply(src, ours);
  cv::Mat expected;
  cv::resize(src, expected, size, 0, 0, cv::INTER_LINEAR);
  EXPECT_EQ(cv::countNonZero(ours != expected), 0) << src.size() << " -> " << size;
  ours.setTo(kMarker);
  EXPECT_EQ(cv::countNonZero(buffer != kMarker), 0) << "written outside the destination, " << size;
}

// The pyramid chain: each level resized from the one above, as OrbExtractor does.
void check_pyramid(const cv::Mat& image) {
  std::vector<LinearResize> resizes(8);
  for (int frame = 0; frame < 2; ++frame) {  // the second time reuses the plans
    cv::Mat level = frame == 0 ? image : cv::Mat(255 - image);
    for (int l = 1; l < 8; ++l) {
      const cv::Size size(static_cast<int>(std::lround(image.cols / std::pow(1.2, l))),
                          static_cast<int>(std::lround(image.rows / std::pow(1.2, l))));
      expect_same_as_opencv(resizes[static_cast<std::size_t>(l)], level, size);
      cv::Mat smaller;
      cv::resize(level, smaller, size, 0, 0, cv::INTER_LINEAR);
      level = smaller;
    }
  }
}

TEST(LinearResize, EqualsOpenCvOnPyramidsOfTexture) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = test::load_texture();
  check_pyramid(texture(cv::Rect(0, 0, 752, 480)).clone());
  cv::Mat wide;
  cv::resize(texture, wide, cv::Size(1241, 376), 0, 0, cv::INTER_AREA);
  check_pyramid(wide);
}

TEST(LinearResize, EqualsOpenCvOnNoiseAndSaturatedImages) {
  check_pyramid(noise_image(752, 480, 1, false));
  check_pyramid(noise_image(1241, 376, 2, true));
  check_pyramid(noise_image(317, 203, 3, false));  // odd sizes: vector tails everywhere
}

TEST(LinearResize, EqualsOpenCvForOtherRatiosAndTinyImages) {
  LinearResize resize;  // one object, sizes changing between calls
  const cv::Mat src = noise_image(517, 333, 4, false);
  for (double ratio : {1.0, 1.05, 1.5, 1.99, 2.0, 2.5, 3.7}) {
    expect_same_as_opencv(
        resize, src,
        cv::Size(static_cast<int>(std::lround(src.cols / ratio)), static_cast<int>(std::lround(src.rows / ratio))));
  }
  expect_same_as_opencv(resize, src, cv::Size(40, 300));  // different ratios per direction
  expect_same_as_opencv(resize, noise_image(9, 7, 5, false), cv::Size(7, 5));
  expect_same_as_opencv(resize, noise_image(40, 30, 6, false), cv::Size(1, 1));
  expect_same_as_opencv(resize, noise_image(40, 30, 7, false), cv::Size(80, 45));  // upscale: OpenCV's own
}

TEST(LinearResize, RejectsWrongTypes) {
  LinearResize resize;
  cv::Mat colour(10, 10, CV_8UC3);
  cv::Mat grey(5, 5, CV_8UC1);
  EXPECT_THROW(resize.apply(colour, grey), std::invalid_argument);
  EXPECT_THROW(resize.apply(grey, colour), std::invalid_argument);
  cv::Mat empty;
  EXPECT_THROW(resize.apply(empty, grey), std::invalid_argument);
}

// Every source width from 16 to 140 with destination widths around the pyramid's ratios: the last
// columns (the overlapping tail blocks of both passes, the clamped last column) at every alignment.
TEST(LinearResize, EqualsOpenCvForEverySourceWidth) {
  LinearResize resize;
  for (int width = 16; width <= 140; ++width) {
    const cv::Mat src = noise_image(width, 9, static_cast<unsigned>(width), width % 3 == 0);
    for (double ratio : {1.0, 1.2, 1.44, 2.0}) {
      const int dst_width = static_cast<int>(std::lround(width / ratio));
      expect_same_as_opencv(resize, src, cv::Size(dst_width, 7));
    }
  }
}

}  // namespace
}  // namespace heslam

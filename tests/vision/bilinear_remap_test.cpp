// BilinearRemap against cv::remap (INTER_LINEAR, BORDER_CONSTANT 0, CV_16SC2 maps): the same pixels,
// inside the image, across its borders, entirely outside it, at every 1/32 px fraction.
#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "components/core/camera/bilinear_remap.hpp"

namespace heslam {
namespace {

cv::Mat random_image(cv::Size size, int seed) {
  cv::Mat image(size, CV_8UC1);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  // Saturated pixels too: the extreme values must round the same way.
  image(cv::Rect(0, 0, size.width / 4, size.height / 4)).setTo(255);
  return image;
}

void expect_same_as_opencv(const cv::Mat& src, const cv::Mat& map_x, const cv::Mat& map_y) {
  cv::Mat map_xy, map_frac;
  cv::convertMaps(map_x, map_y, map_xy, map_frac, CV_16SC2);
  cv::Mat expected;
  cv::remap(src, expected, map_xy, map_frac, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  const BilinearRemap remap(map_xy, map_frac, src.size());
  cv::Mat actual;
  remap.apply(src, actual);
  ASSERT_EQ(actual.size(), expected.size());
  ASSERT_EQ(actual.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(actual, expected, cv::NORM_INF), 0.0);
  // A second call writes into the same buffer.
  const std::uint8_t* data = actual.data;
  remap.apply(src, actual);
  EXPECT_EQ(actual.data, data);
  EXPECT_EQ(cv::norm(actual, expected, cv::NORM_INF), 0.0);
}

TEST(BilinearRemap, RotatedScaledMapAcrossTheBordersGivesCvRemapsPixels) {
  const cv::Size size(173, 121);  // not a multiple of the vector block
  const cv::Mat src = random_image(size, 7);
  cv::Mat map_x(size, CV_32FC1), map_y(size, CV_32FC1);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      // Rotation by 0.3 rad and scale 1.3 about the centre: corners map far outside the image.
      const float dx = static_cast<float>(x) - 86.f, dy = static_cast<float>(y) - 60.f;
      map_x.at<float>(y, x) = 86.f + 1.3f * (0.955336f * dx - 0.295520f * dy);
      map_y.at<float>(y, x) = 60.f + 1.3f * (0.295520f * dx + 0.955336f * dy);
    }
  }
  expect_same_as_opencv(src, map_x, map_y);
}

TEST(BilinearRemap, EveryFractionAndTheLastRowsAndColumns) {
  const cv::Size size(64, 48);
  const cv::Mat src = random_image(size, 11);
  cv::Mat map_x(size, CV_32FC1), map_y(size, CV_32FC1);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      // All 32 x 32 fractions over the image, shifted so the last columns and rows read across the
      // right and bottom edges (and the first ones across the left and top).
      map_x.at<float>(y, x) = static_cast<float>(x) - 0.5f + static_cast<float>(x % 32) / 32.f;
      map_y.at<float>(y, x) = static_cast<float>(y) - 0.5f + static_cast<float>((x / 2 + y) % 32) / 32.f;
    }
  }
  expect_same_as_opencv(src, map_x, map_y);
}

TEST(BilinearRemap, ShiftedMapLikeARectificationGivesCvRemapsPixels) {
  // About one source pixel per output pixel along a row, as a rectification map: most blocks read
  // their neighbourhoods from one 16-byte window per half block; the shift crosses the borders.
  const cv::Size size(96, 40);
  const cv::Mat src = random_image(size, 5);
  cv::Mat map_x(size, CV_32FC1), map_y(size, CV_32FC1);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      map_x.at<float>(y, x) = 1.02f * static_cast<float>(x) - 3.22f;
      map_y.at<float>(y, x) = static_cast<float>(y) + 0.01f * static_cast<float>(x) - 1.4f;
    }
  }
  expect_same_as_opencv(src, map_x, map_y);
}

TEST(BilinearRemap, MapEntirelyOutsideGivesZeros) {
  const cv::Mat src = random_image(cv::Size(40, 30), 3);
  const cv::Mat map_x(src.size(), CV_32FC1, cv::Scalar(-5.f));
  const cv::Mat map_y(src.size(), CV_32FC1, cv::Scalar(100.f));
  expect_same_as_opencv(src, map_x, map_y);
}

TEST(BilinearRemap, WrongInputIsOneClearError) {
  cv::Mat map_x(cv::Size(16, 8), CV_32FC1, cv::Scalar(1.f)), map_y = map_x.clone();
  cv::Mat map_xy, map_frac;
  cv::convertMaps(map_x, map_y, map_xy, map_frac, CV_16SC2);
  EXPECT_THROW(BilinearRemap(map_x, map_y, cv::Size(16, 8)), std::invalid_argument);
  const BilinearRemap remap(map_xy, map_frac, cv::Size(16, 8));
  cv::Mat out;
  EXPECT_THROW(remap.apply(cv::Mat(cv::Size(15, 8), CV_8UC1), out), std::invalid_argument);
  EXPECT_THROW(remap.apply(cv::Mat(cv::Size(16, 8), CV_16UC1), out), std::invalid_argument);
}

}  // namespace
}  // namespace heslam

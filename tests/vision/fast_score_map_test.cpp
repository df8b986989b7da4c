// FastScoreMap reports exactly the corners and responses of cv::FAST (threshold, non-maximum
// suppression) on the same sub-image: whole areas and small grid cells, textured, noisy and
// saturated images, thresholds from 1 to 60.
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>

#include "components/core/feature/fast_score_map.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

constexpr int kRing = FastScoreMap::kRadiusPx;

std::vector<ScoredPoint> opencv_corners(const cv::Mat& image, const cv::Rect& region, int threshold) {
  const cv::Rect grown(region.x - kRing, region.y - kRing, region.width + 2 * kRing, region.height + 2 * kRing);
  std::vector<cv::KeyPoint> keypoints;
  cv::FAST(image(grown), keypoints, threshold, /*nonmaxSuppression=*/true);
  std::vector<ScoredPoint> points;
  for (const cv::KeyPoint& k : keypoints) {
    points.push_back({k.pt.x + static_cast<float>(grown.x), k.pt.y + static_cast<float>(grown.y), k.response});
  }
  return points;
}

void expect_same_corners(const cv::Mat& image, const FastScoreMap& map, const cv::Rect& region, int threshold) {
  std::vector<ScoredPoint> ours;
  map.corners(region, threshold, ours);
  const std::vector<ScoredPoint> reference = opencv_corners(image, region, threshold);
  ASSERT_EQ(ours.size(), reference.size()) << "region " << region << " threshold " << threshold;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    ASSERT_EQ(ours[i].x, reference[i].x) << "corner " << i << " region " << region << " threshold " << threshold;
    ASSERT_EQ(ours[i].y, reference[i].y) << "corner " << i << " region " << region << " threshold " << threshold;
    ASSERT_EQ(ours[i].response, reference[i].response) << "corner " << i << " threshold " << threshold;
  }
}

// The whole area and a grid of 30 px cells (ORB-SLAM2's), plus cells narrower than a SIMD vector.
void check_image(const cv::Mat& image, int expected_min_corners) {
  const cv::Rect area(16, 16, image.cols - 32, image.rows - 32);
  FastScoreMap map;
  map.compute(image, area);
  for (int threshold : {1, 7, 20, 60}) expect_same_corners(image, map, area, threshold);
  std::vector<ScoredPoint> all;
  map.corners(area, 7, all);
  EXPECT_GE(static_cast<int>(all.size()), expected_min_corners);
  for (int y = area.y; y < area.y + area.height; y += 30) {
    for (int x = area.x; x < area.x + area.width; x += 30) {
      const cv::Rect cell = cv::Rect(x, y, 30, 30) & area;
      expect_same_corners(image, map, cell, 7);
      expect_same_corners(image, map, cell, 20);
    }
  }
  for (const cv::Rect& odd : {cv::Rect(area.x, area.y, 1, 1), cv::Rect(area.x + 5, area.y + 7, 13, 3),
                              cv::Rect(area.x + 40, area.y + 9, 31, 17)}) {
    expect_same_corners(image, map, odd, 7);
  }
}

TEST(FastScoreMap, MatchesOpenCvFastOnTexture) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = test::load_texture();
  check_image(texture(cv::Rect(0, 0, 752, 480)).clone(), 1000);
}

TEST(FastScoreMap, MatchesOpenCvFastOnNoiseAndSaturatedPixels) {
  std::mt19937 rng(7);
  cv::Mat noise(203, 317, CV_8UC1);  // odd sizes: vector tails
  std::uniform_int_distribution<int> grey(0, 255);
  for (int y = 0; y < noise.rows; ++y) {
    for (int x = 0; x < noise.cols; ++x) noise.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(grey(rng));
  }
  check_image(noise, 1000);
  // Only 0 and 255: every difference saturates.
  cv::Mat binary = noise > 127;
  check_image(binary, 100);
}

TEST(FastScoreMap, ScoresAViewIntoAPaddedImage) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = test::load_texture();
  cv::Mat padded;
  cv::copyMakeBorder(texture(cv::Rect(100, 100, 200, 150)), padded, 19, 19, 19, 19, cv::BORDER_REFLECT_101);
  const cv::Mat view = padded(cv::Rect(19, 19, 200, 150));
  FastScoreMap map;
  // The ring around the area may lie in the parent's border.
  const cv::Rect area(0, 0, 200, 150);
  map.compute(view, area);
  std::vector<ScoredPoint> ours;
  map.corners(area, 7, ours);
  const std::vector<ScoredPoint> reference = opencv_corners(padded, area + cv::Point(19, 19), 7);
  ASSERT_EQ(ours.size(), reference.size());
  ASSERT_GT(ours.size(), 100u);
  for (std::size_t i = 0; i < ours.size(); ++i) {
    EXPECT_EQ(ours[i].x + 19.f, reference[i].x);
    EXPECT_EQ(ours[i].y + 19.f, reference[i].y);
    EXPECT_EQ(ours[i].response, reference[i].response);
  }
  EXPECT_THROW(map.compute(padded, cv::Rect(0, 0, 10, 10)), std::invalid_argument);
}

}  // namespace
}  // namespace heslam

// FastScoreMap reports exactly the corners and responses of cv::FAST (threshold, non-maximum
// suppression) on the same sub-image: whole areas and small grid cells, textured, noisy and
// saturated images, thresholds from 1 to 60; and every pixel's score against the definition.
#include <algorithm>
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

// The FAST-9 score from its definition, one pixel at a time: the largest t such that 9 contiguous
// circle pixels are all brighter than centre + t or all darker than centre - t, i.e. the best arc's
// smallest difference minus 1 (0 when no arc differs at all).
int reference_score(const cv::Mat& image, int x, int y) {
  constexpr int kCircle[16][2] = {{0, 3},  {1, 3},   {2, 2},   {3, 1},   {3, 0},  {3, -1}, {2, -2}, {1, -3},
                                  {0, -3}, {-1, -3}, {-2, -2}, {-3, -1}, {-3, 0}, {-3, 1}, {-2, 2}, {-1, 3}};
  const int v = image.at<std::uint8_t>(y, x);
  int best = 0;
  for (int start = 0; start < 16; ++start) {
    int brighter = 255;
    int darker = 255;
    for (int k = 0; k < 9; ++k) {
      const int* d = kCircle[(start + k) % 16];
      const int p = image.at<std::uint8_t>(y + d[1], x + d[0]);
      brighter = std::min(brighter, std::max(p - v, 0));
      darker = std::min(darker, std::max(v - p, 0));
    }
    best = std::max({best, brighter, darker});
  }
  return std::max(best - 1, 0);
}

TEST(FastScoreMap, EveryScoreEqualsTheArcDefinition) {
  std::mt19937 rng(13);
  std::uniform_int_distribution<int> grey(0, 255);
  cv::Mat noise(61, 131, CV_8UC1);  // odd width: vector tails
  for (int y = 0; y < noise.rows; ++y) {
    for (int x = 0; x < noise.cols; ++x) noise.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(grey(rng));
  }
  // Smooth ramps with a few steps (arcs of equal differences), and only 0 and 255 (saturation).
  cv::Mat ramps(noise.size(), CV_8UC1);
  for (int y = 0; y < ramps.rows; ++y) {
    for (int x = 0; x < ramps.cols; ++x)
      ramps.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>((x * 7 + (y / 5) * 40) % 256);
  }
  const cv::Mat binary = noise > 127;
  for (const cv::Mat& image : {noise, ramps, binary}) {
    const cv::Rect area(kRing, kRing, image.cols - 2 * kRing, image.rows - 2 * kRing);
    FastScoreMap map;
    map.compute(image, area);
    for (int y = area.y; y < area.y + area.height; ++y) {
      for (int x = area.x; x < area.x + area.width; ++x) {
        ASSERT_EQ(map.score(x, y), reference_score(image, x, y)) << "pixel " << x << ", " << y;
      }
    }
  }
}

}  // namespace
}  // namespace heslam

// ORB extraction: rotation invariance of orientation and descriptors, coverage of the image by the
// quadtree distribution, per-level counts in proportion to level area, a detection region, determinism.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "components/core/feature/orb_extractor.hpp"
#include "components/core/match/feature_grid.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

cv::Mat texture_752x480() {
  const cv::Mat texture = test::load_texture();
  return texture(cv::Rect((texture.cols - 752) / 2, (texture.rows - 480) / 2, 752, 480)).clone();
}

int median(std::vector<int> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

TEST(OrbExtractor, RotatedImageGivesSameDescriptors) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = test::load_texture();
  // A centred square crop, rotated about its centre; only the inner disc is compared.
  const int side = 480;
  const cv::Mat image = texture(cv::Rect((texture.cols - side) / 2, (texture.rows - side) / 2, side, side)).clone();
  const cv::Point2f center(side / 2.f - 0.5f, side / 2.f - 0.5f);
  OrbOptions options;
  options.features = 1000;
  OrbExtractor extractor(options);
  OrbFeatures original;
  extractor.extract(image, original);

  for (const double angle_deg : {30.0, 90.0, 135.0, 250.0}) {
    const cv::Mat rotation = cv::getRotationMatrix2D(center, angle_deg, 1.0);
    cv::Mat rotated;
    cv::warpAffine(image, rotated, rotation, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
    OrbFeatures turned;
    OrbExtractor(options).extract(rotated, turned);
    const FeatureGrid grid(turned.keypoints, side, side);

    std::vector<int> same_point_distance;
    std::vector<double> angle_error_deg;
    for (std::size_t i = 0; i < original.keypoints.size(); ++i) {
      const Keypoint& k = original.keypoints[i];
      if (std::hypot(k.u_px - center.x, k.v_px - center.y) > side * 0.35) continue;
      const double u =
          rotation.at<double>(0, 0) * k.u_px + rotation.at<double>(0, 1) * k.v_px + rotation.at<double>(0, 2);
      const double v =
          rotation.at<double>(1, 0) * k.u_px + rotation.at<double>(1, 1) * k.v_px + rotation.at<double>(1, 2);
      // The same physical corner: detected within 1 px (x scale) on the same level.
      const float radius = 1.f * extractor.scale_pyramid().scale[static_cast<std::size_t>(k.octave)] + 0.5f;
      int best = -1;
      float best_d2 = 1e9f;
      for (int j : grid.in_area(static_cast<float>(u), static_cast<float>(v), radius, k.octave, k.octave)) {
        const float d2 = std::pow(turned.keypoints[j].u_px - static_cast<float>(u), 2.f) +
                         std::pow(turned.keypoints[j].v_px - static_cast<float>(v), 2.f);
        if (d2 < best_d2) {
          best_d2 = d2;
          best = j;
        }
      }
      if (best < 0) continue;
      same_point_distance.push_back(hamming_distance(original.descriptors[i], turned.descriptors[best]));
      // getRotationMatrix2D turns counter-clockwise on screen: image angles (y down) decrease.
      double error = std::fmod(turned.keypoints[best].angle_deg - (k.angle_deg - angle_deg) + 720.0, 360.0);
      angle_error_deg.push_back(std::min(error, 360.0 - error));
    }
    ASSERT_GT(same_point_distance.size(), 50u) << "angle " << angle_deg;
    std::vector<int> random_distance;
    std::mt19937 rng(1);
    for (int k = 0; k < 500; ++k) {
      random_distance.push_back(hamming_distance(original.descriptors[rng() % original.descriptors.size()],
                                                 turned.descriptors[rng() % turned.descriptors.size()]));
    }
    std::sort(angle_error_deg.begin(), angle_error_deg.end());
    const int same = median(same_point_distance);
    const int random = median(random_distance);
    std::printf(
        "rotation %5.1f deg: %zu corresponding keypoints, median Hamming %d (random pairs %d), "
        "median orientation error %.2f deg\n",
        angle_deg, same_point_distance.size(), same, random, angle_error_deg[angle_error_deg.size() / 2]);
    EXPECT_LT(same, 40) << "angle " << angle_deg;
    EXPECT_GT(random, 100) << "angle " << angle_deg;
    EXPECT_LT(angle_error_deg[angle_error_deg.size() / 2], 5.0) << "angle " << angle_deg;
  }
}

TEST(OrbExtractor, FeaturesCoverTheImageAndLevelsFollowArea) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat image = texture_752x480();
  OrbExtractor extractor;  // EuRoC defaults: 1200 features, 8 x 1.2
  OrbFeatures features;
  extractor.extract(image, features);
  ASSERT_EQ(features.keypoints.size(), features.descriptors.size());
  EXPECT_GE(features.keypoints.size(), 1150u);
  EXPECT_LE(features.keypoints.size(), 1200u + 3u * 8u);

  // Wanted per level: a geometric series in the area ratio 1/1.44 summing to 1200.
  const std::vector<int>& wanted = extractor.features_per_level();
  EXPECT_EQ(std::accumulate(wanted.begin(), wanted.end(), 0), 1200);
  for (std::size_t l = 1; l + 1 < wanted.size(); ++l) {
    EXPECT_NEAR(static_cast<double>(wanted[l]) / wanted[l - 1], 1.0 / 1.44, 0.02) << "level " << l;
  }
  std::vector<int> per_level(8, 0);
  for (const Keypoint& k : features.keypoints) ++per_level[static_cast<std::size_t>(k.octave)];
  for (std::size_t l = 0; l < 8; ++l) {
    EXPECT_GE(per_level[l], static_cast<int>(0.9 * wanted[l])) << "level " << l;
    EXPECT_LE(per_level[l], wanted[l] + 3) << "level " << l;
  }

  // Coverage: every 71x74 px cell inside the border that has texture (>= 10 FAST corners at the
  // initial threshold on level 0) holds keypoints.
  const int cols = 10;
  const int rows = 6;
  const float cell_w = (752.f - 2 * kOrbBorderPx) / cols;
  const float cell_h = (480.f - 2 * kOrbBorderPx) / rows;
  auto cell_of = [&](float u, float v) {
    const int c = std::clamp(static_cast<int>((u - kOrbBorderPx) / cell_w), 0, cols - 1);
    const int r = std::clamp(static_cast<int>((v - kOrbBorderPx) / cell_h), 0, rows - 1);
    return static_cast<std::size_t>(r * cols + c);
  };
  std::vector<int> count(static_cast<std::size_t>(cols * rows), 0);
  std::vector<int> corners(count.size(), 0);
  for (const Keypoint& k : features.keypoints) ++count[cell_of(k.u_px, k.v_px)];
  std::vector<cv::KeyPoint> fast;
  cv::FAST(image, fast, OrbOptions().fast_threshold_initial, true);
  for (const cv::KeyPoint& k : fast) ++corners[cell_of(k.pt.x, k.pt.y)];
  int textured = 0;
  int covered = 0;
  for (std::size_t c = 0; c < count.size(); ++c) {
    if (corners[c] < 10) continue;  // a handful of corners is noise, not texture
    ++textured;
    covered += count[c] > 0 ? 1 : 0;
    EXPECT_GT(count[c], 0) << "cell " << c << " has " << corners[c] << " FAST corners but no keypoint";
  }
  const int highest = *std::max_element(count.begin(), count.end());
  std::printf("%d of %d textured cells (of %d) hold keypoints; at most %d per cell, mean %.1f\n", covered, textured,
              cols * rows, highest, features.keypoints.size() / double(cols * rows));
  EXPECT_GT(textured, cols * rows / 2);
  EXPECT_LE(highest, 4 * static_cast<int>(features.keypoints.size()) / (cols * rows));

  // Keypoints stay inside the detection area and angles inside [0, 360).
  for (const Keypoint& k : features.keypoints) {
    EXPECT_GE(k.angle_deg, 0.f);
    EXPECT_LT(k.angle_deg, 360.f);
    EXPECT_TRUE(k.u_px >= 0.f && k.u_px < 752.f && k.v_px >= 0.f && k.v_px < 480.f);
  }
}

TEST(OrbExtractor, LowContrastCellsFallBackToTheMinimumThreshold) {
  HESLAM_REQUIRE_TEXTURE();
  // Left half full contrast, right half at 1/10 contrast: FAST 20 finds little on the right, the
  // per-cell fallback to 7 gives the right half keypoints where a single threshold would not.
  cv::Mat image = texture_752x480();
  cv::Mat right_half = image.colRange(376, 752);
  right_half.convertTo(right_half, CV_8U, 0.1, 115);
  auto right_share = [&](const OrbOptions& options) {
    OrbFeatures features;
    OrbExtractor(options).extract(image, features);
    int right = 0;
    for (const Keypoint& k : features.keypoints) right += k.u_px >= 376.f ? 1 : 0;
    return static_cast<double>(right) / static_cast<double>(features.keypoints.size());
  };
  OrbOptions single_threshold;
  single_threshold.fast_threshold_min = single_threshold.fast_threshold_initial;
  const double with_fallback = right_share(OrbOptions());
  const double without_fallback = right_share(single_threshold);
  std::printf("share of keypoints on the low-contrast half: %.2f with the 20/7 fallback, %.2f with 20 only\n",
              with_fallback, without_fallback);
  EXPECT_GT(with_fallback, 0.15);
  EXPECT_GT(with_fallback, 1.5 * without_fallback);
}

// The pyramid is built in place (each level resized straight into its padded buffer, the border
// reflected around it): every padded level must equal cv::resize of the level above followed by
// cv::copyMakeBorder(BORDER_REFLECT_101), as before. 60x40 also takes the path for levels smaller
// than the border.
TEST(OrbExtractor, PyramidLevelsAndBordersEqualOpenCvs) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = texture_752x480();
  for (const cv::Mat& image : {texture, cv::Mat(texture(cv::Rect(100, 100, 60, 40)).clone())}) {
    OrbExtractor extractor;
    for (int frame = 0; frame < 2; ++frame) {  // the second frame reuses the buffers
      OrbFeatures features;
      extractor.extract(frame == 0 ? image : cv::Mat(255 - image), features);
      cv::Mat level = frame == 0 ? image : cv::Mat(255 - image);
      ASSERT_EQ(features.pyramid.size(), static_cast<std::size_t>(extractor.options().levels));
      for (std::size_t l = 0; l < features.pyramid.size(); ++l) {
        if (l > 0) {
          cv::Mat smaller;
          cv::resize(level, smaller, features.pyramid[l].size(), 0, 0, cv::INTER_LINEAR);
          level = smaller;
        }
        cv::Mat expected;
        cv::copyMakeBorder(level, expected, kOrbBorderPx, kOrbBorderPx, kOrbBorderPx, kOrbBorderPx,
                           cv::BORDER_REFLECT_101);
        cv::Mat padded = features.pyramid[l];
        padded.adjustROI(kOrbBorderPx, kOrbBorderPx, kOrbBorderPx, kOrbBorderPx);
        ASSERT_EQ(padded.size(), expected.size()) << "level " << l;
        EXPECT_EQ(cv::countNonZero(padded != expected), 0) << "level " << l << " of " << image.size();
      }
    }
  }
}

// set_region: every keypoint inside the region (at level 0), the wanted count spread over it, and an
// empty region gives back the whole-image extraction exactly.
TEST(OrbExtractor, RegionHoldsEveryKeypointAndTheWantedCount) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat image = texture_752x480();
  cv::Mat region = cv::Mat::zeros(image.size(), CV_8UC1);
  cv::circle(region, cv::Point(500, 240), 150, cv::Scalar(255), cv::FILLED);
  OrbExtractor whole;
  OrbFeatures reference;
  whole.extract(image, reference);

  OrbExtractor extractor;
  OrbFeatures inside;
  extractor.set_region(region, 300);
  extractor.extract(image, inside);
  // The quadtree may hand out a few more than wanted, as over the whole image (1200 -> 1204-1208).
  EXPECT_LE(inside.keypoints.size(), 315u);
  EXPECT_GE(inside.keypoints.size(), 270u);  // graf1 has texture everywhere in the disc
  int outside = 0;
  int right_half = 0;
  for (const Keypoint& k : inside.keypoints) {
    const int x = std::min(static_cast<int>(std::lround(k.u_px)), image.cols - 1);
    const int y = std::min(static_cast<int>(std::lround(k.v_px)), image.rows - 1);
    if (region.at<std::uint8_t>(y, x) == 0) ++outside;
    if (k.u_px >= 500.f) ++right_half;
  }
  EXPECT_EQ(outside, 0);
  // Spread over the disc, not piled on one side of it.
  EXPECT_GT(right_half, static_cast<int>(inside.keypoints.size()) / 3);
  EXPECT_LT(right_half, 2 * static_cast<int>(inside.keypoints.size()) / 3);

  extractor.set_region(cv::Mat(), 0);
  OrbFeatures again;
  extractor.extract(image, again);
  ASSERT_EQ(again.keypoints.size(), reference.keypoints.size());
  for (std::size_t i = 0; i < again.keypoints.size(); ++i) {
    EXPECT_EQ(again.keypoints[i].u_px, reference.keypoints[i].u_px);
    EXPECT_EQ(again.descriptors[i], reference.descriptors[i]);
  }
  EXPECT_THROW(extractor.set_region(cv::Mat::zeros(image.size(), CV_32FC1), 10), std::invalid_argument);
}

TEST(OrbExtractor, Deterministic) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat image = texture_752x480();
  OrbExtractor extractor;
  OrbFeatures a;
  OrbFeatures b;
  extractor.extract(image, a);
  OrbExtractor().extract(image, b);
  ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
  for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].u_px, b.keypoints[i].u_px);
    EXPECT_EQ(a.keypoints[i].angle_deg, b.keypoints[i].angle_deg);
    EXPECT_EQ(a.descriptors[i], b.descriptors[i]);
  }
}

}  // namespace
}  // namespace heslam

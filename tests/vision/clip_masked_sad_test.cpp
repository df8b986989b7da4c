// ClipMaskedSad and clipped_top_level (issue 17 §1): windows whose two images are clipped at
// different places compare only their unclipped pixels.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/match/clip_edge.hpp"
#include "components/core/match/clip_masked_sad.hpp"

namespace heslam {
namespace {

constexpr int kHalfWindow = 5;
constexpr int kSearch = 5;
constexpr int kTrueDisparity = 2;  // right(u) = left(u + 2)

struct Pair {
  cv::Mat left, right;
  int ul = 40, vl = 30;  // left keypoint
  int ur0 = ul - kTrueDisparity;
};

// Textured (0-200) pair with the right image the left shifted by kTrueDisparity pixels.
Pair textured_pair() {
  Pair p;
  cv::Mat scene(60, 100, CV_8UC1);
  cv::RNG rng(17);
  rng.fill(scene, cv::RNG::UNIFORM, 0, 200);
  p.left = scene.clone();
  p.right = cv::Mat(scene.size(), CV_8UC1);
  for (int v = 0; v < scene.rows; ++v) {
    for (int u = 0; u < scene.cols; ++u) {
      p.right.at<std::uint8_t>(v, u) = scene.at<std::uint8_t>(v, std::min(u + kTrueDisparity, scene.cols - 1));
    }
  }
  return p;
}

std::vector<int> masked_costs(const Pair& p, const ClipLevels& levels, bool* masked) {
  std::vector<int> sads(2 * kSearch + 1, -1);
  ClipMaskedSad sad(kHalfWindow, kSearch);
  *masked = sad.compute(p.left.ptr<std::uint8_t>(p.vl) + p.ul, static_cast<int>(p.left.step1()),
                        p.right.ptr<std::uint8_t>(p.vl), p.ur0, static_cast<int>(p.right.step1()), levels, sads);
  return sads;
}

TEST(ClipMaskedSad, WithoutClippedPixelsLeavesThePlainSad) {
  const Pair p = textured_pair();
  bool masked = true;
  const std::vector<int> sads = masked_costs(p, {255, 255}, &masked);
  EXPECT_FALSE(masked);
  EXPECT_EQ(sads[0], -1);  // untouched
}

// Each image clipped (to 255) from a different scene column on: the left from the keypoint's column
// + 3, the right from 9 scene columns further. Over the unclipped pixels the true shift matches
// exactly (cost 0); the plain SAD counts the left's plateau against texture there (on this random
// texture its minimum still lies at the true shift, the plateau being the same at every shift).
TEST(ClipMaskedSad, DifferentClipEdgesKeepTheTrueShift) {
  Pair p = textured_pair();
  for (int v = 0; v < p.left.rows; ++v) {
    for (int u = p.ul + 3; u < p.left.cols; ++u) p.left.at<std::uint8_t>(v, u) = 255;
    for (int u = p.ur0 + 10; u < p.right.cols; ++u) p.right.at<std::uint8_t>(v, u) = 255;
  }
  bool masked = false;
  const std::vector<int> sads = masked_costs(p, {255, 255}, &masked);
  ASSERT_TRUE(masked);
  const auto best = std::min_element(sads.begin(), sads.end());
  EXPECT_EQ(best - sads.begin(), kSearch) << "the true shift is 0";
  EXPECT_EQ(*best, 0);

  // For the record: the plain mean-normalized SAD's minimum over the same shifts.
  std::vector<int> plain;
  const int n = (2 * kHalfWindow + 1) * (2 * kHalfWindow + 1);
  for (int shift = -kSearch; shift <= kSearch; ++shift) {
    int sum_l = 0;
    int sum_r = 0;
    for (int dv = -kHalfWindow; dv <= kHalfWindow; ++dv) {
      for (int du = -kHalfWindow; du <= kHalfWindow; ++du) {
        sum_l += p.left.at<std::uint8_t>(p.vl + dv, p.ul + du);
        sum_r += p.right.at<std::uint8_t>(p.vl + dv, p.ur0 + shift + du);
      }
    }
    const int offset = (sum_l - sum_r) / n;
    int sad = 0;
    for (int dv = -kHalfWindow; dv <= kHalfWindow; ++dv) {
      for (int du = -kHalfWindow; du <= kHalfWindow; ++du) {
        sad += std::abs(p.left.at<std::uint8_t>(p.vl + dv, p.ul + du) -
                        p.right.at<std::uint8_t>(p.vl + dv, p.ur0 + shift + du) - offset);
      }
    }
    plain.push_back(sad);
  }
  const auto plain_best = std::min_element(plain.begin(), plain.end());
  std::printf("plain SAD: minimum at shift %d (cost %d at the true shift 0, %d there)\n",
              static_cast<int>(plain_best - plain.begin()) - kSearch, plain[kSearch], *plain_best);
  EXPECT_GT(plain[kSearch], 0);
}

// Fewer than half of the window's pixels usable at some shift: the plain SAD applies.
TEST(ClipMaskedSad, MostlyClippedWindowFallsBack) {
  Pair p = textured_pair();
  for (int v = 0; v < p.left.rows; ++v) {
    for (int u = p.ul - 3; u < p.left.cols; ++u) p.left.at<std::uint8_t>(v, u) = 255;
  }
  bool masked = true;
  masked_costs(p, {255, 255}, &masked);
  EXPECT_FALSE(masked);
}

TEST(ClippedTopLevel, PlateauOnlyWhenLargeEnough) {
  cv::Mat image(100, 100, CV_8UC1, cv::Scalar(90));
  image(cv::Rect(0, 0, 100, 5)).setTo(200);  // 5 % at the top level
  EXPECT_EQ(clipped_top_level(image, 0.01), 200);
  EXPECT_EQ(clipped_top_level(image, 0.10), 256);
  image.at<std::uint8_t>(50, 50) = 201;  // a single brighter pixel: the top level holds 0.01 %
  EXPECT_EQ(clipped_top_level(image, 0.01), 256);
}

// mark_near_clip: a stereo match is near a clip edge when the box around its left keypoint holds a
// pixel of the left plateau, or the box around its right match one of the right plateau; the box is
// 6 px x the keypoint's level scale; features without a stereo match are never marked.
TEST(MarkNearClip, EitherImagesPlateauInTheBoxMarksAStereoMatch) {
  cv::Mat left_clipped(100, 200, CV_8UC1, cv::Scalar(0));
  cv::Mat right_clipped(100, 200, CV_8UC1, cv::Scalar(0));
  left_clipped(cv::Rect(0, 0, 50, 100)).setTo(1);     // left plateau: u < 50
  right_clipped(cv::Rect(150, 0, 50, 100)).setTo(1);  // right plateau: u >= 150
  StereoFeatures features;
  features.pyramid = ScalePyramid::make(2, 2.f);
  const auto add = [&](float u, float u_right, int octave) {
    features.keypoints.push_back(Keypoint{u, 50.f, 0.f, 1.f, octave});
    features.descriptors.push_back(Descriptor{});
    features.u_right_px.push_back(u_right);
    features.depth_m.push_back(u_right >= 0.f ? 2.f : kNoStereo);
  };
  add(54.f, 40.f, 0);       // left box [48, 60] reaches the left plateau
  add(54.f, kNoStereo, 0);  // the same place without a stereo match
  add(100.f, 146.f, 0);     // right box [140, 152] reaches the right plateau
  add(100.f, 80.f, 0);      // clear of both
  add(70.f, 60.f, 1);       // octave 1: left box [58, 82] clear, right box [48, 72] clear
  add(62.f, 40.f, 1);       // octave 1: left box [50, 74] clear; right box [28, 52] holds no right plateau
  add(60.f, 50.f, 1);       // octave 1: left box [48, 72] reaches the left plateau
  mark_near_clip(left_clipped, right_clipped, ClipEdgeOptions{}, features);
  EXPECT_EQ(features.near_clip, (std::vector<std::uint8_t>{1, 0, 1, 0, 0, 0, 1}));
  ClipEdgeOptions off;
  off.radius_px = 0;
  mark_near_clip(left_clipped, right_clipped, off, features);
  EXPECT_EQ(features.near_clip, std::vector<std::uint8_t>(7, 0));
}

}  // namespace
}  // namespace heslam

// StereoFeaturePipelineOptions::left_only_features on real MH01 pairs: where the right camera
// saturates and the left still sees, the left's own texture gives monocular keypoints, appended after
// the stereo keypoints, which stay exactly as they were; equally exposed pairs and a left camera
// saturated by itself get none.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

StereoFeatures run(const PinholeStereo& camera, float left_only_features, const cv::Mat& left, const cv::Mat& right) {
  StereoFeaturePipelineOptions options;
  options.parallel = false;
  options.left_only_features = left_only_features;
  StereoFeaturePipeline pipeline(camera, options);
  return pipeline.process(left, right);
}

// The first `count` keypoints of both are the same, with the same stereo results.
void expect_same_prefix(const StereoFeatures& a, const StereoFeatures& b, std::size_t count) {
  ASSERT_GE(a.size(), count);
  ASSERT_GE(b.size(), count);
  for (std::size_t i = 0; i < count; ++i) {
    ASSERT_EQ(a.keypoints[i].u_px, b.keypoints[i].u_px) << i;
    ASSERT_EQ(a.keypoints[i].v_px, b.keypoints[i].v_px) << i;
    ASSERT_EQ(a.descriptors[i], b.descriptors[i]) << i;
    ASSERT_EQ(a.u_right_px[i], b.u_right_px[i]) << i;
    ASSERT_EQ(a.depth_m[i], b.depth_m[i]) << i;
  }
}

TEST(LeftOnlyFeatures, RightCameraSaturatedGivesMonocularKeypointsWhereOnlyTheLeftSees) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  PinholeStereo camera;
  const std::vector<test::RectifiedPair> pairs = test::load_euroc_pairs({20, 80, 140}, &camera);
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const test::RectifiedPair& pair = pairs[p];
    cv::Mat right_x4;
    pair.right.convertTo(right_x4, CV_8U, 4.0);  // 40-70 % of it saturates
    const StereoFeatures plain = run(camera, 0.f, pair.left, right_x4);
    const StereoFeatures with = run(camera, 1.f, pair.left, right_x4);
    expect_same_prefix(plain, with, plain.size());
    const std::size_t added = with.size() - plain.size();
    // Where the left is clipped to the right's range: about the saturated share of the 1200.
    EXPECT_GT(added, 200u) << "pair " << p;
    EXPECT_LT(added, 1200u) << "pair " << p;
    int on_saturated_right = 0;
    for (std::size_t i = plain.size(); i < with.size(); ++i) {
      EXPECT_FALSE(with.has_stereo(i)) << i;
      const Keypoint& k = with.keypoints[i];
      const int x = std::min(static_cast<int>(std::lround(k.u_px)), right_x4.cols - 1);
      const int y = std::min(static_cast<int>(std::lround(k.v_px)), right_x4.rows - 1);
      // The right's saturation is offset by the disparity: look a little to the left of the keypoint.
      bool saturated = false;
      for (int dx = 0; dx <= 40 && !saturated; dx += 4) {
        saturated = right_x4.at<std::uint8_t>(y, std::max(x - dx, 0)) == 255;
      }
      on_saturated_right += saturated ? 1 : 0;
    }
    // The region is where the equalized left sits on the plateau the right's range put it on, which
    // follows the tone curve rather than each pixel's counterpart (measured 93-99 %).
    EXPECT_GT(on_saturated_right, static_cast<int>(0.85 * static_cast<double>(added))) << "pair " << p;
    const auto with_depth = std::count_if(plain.depth_m.begin(), plain.depth_m.end(), [](float d) { return d > 0.f; });
    std::printf(
        "[ figures  ] MH01 pair %zu, right x4: %zu stereo-side keypoints (%ld with depth), %zu left-only, "
        "%d of them where the right saturates\n",
        p, plain.size(), static_cast<long>(with_depth), added, on_saturated_right);
  }
}

TEST(LeftOnlyFeatures, NoneForEquallyExposedPairsOrALeftSaturatedByItself) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  PinholeStereo camera;
  const std::vector<test::RectifiedPair> pairs = test::load_euroc_pairs({20, 140}, &camera);
  for (const test::RectifiedPair& pair : pairs) {
    const StereoFeatures plain = run(camera, 0.f, pair.left, pair.right);
    const StereoFeatures with = run(camera, 1.f, pair.left, pair.right);
    ASSERT_EQ(with.size(), plain.size());
    expect_same_prefix(plain, with, plain.size());

    // Left x4: the left's plateau is its own saturation, with no texture behind it.
    cv::Mat left_x4;
    pair.left.convertTo(left_x4, CV_8U, 4.0);
    const StereoFeatures left_plain = run(camera, 0.f, left_x4, pair.right);
    const StereoFeatures left_with = run(camera, 1.f, left_x4, pair.right);
    expect_same_prefix(left_plain, left_with, left_plain.size());
    EXPECT_LT(left_with.size() - left_plain.size(), 20u);
  }
}

}  // namespace
}  // namespace heslam

// The cameras' photometric relation measured on stereo matches (feature/stereo_tone.hpp): known gains
// and offsets on a synthetic textured pair, the clipped patches left out, the tracker's median, age and
// exposure-step rules; and on real EuRoC MH01 pairs, that left x4 / right x1 and left x0.35 / right x2
// measure 4 and 0.175 times what the equally exposed pair measures.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "components/core/feature/stereo_tone.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr int kDisparityPx = 12;

// A smooth random scene in [20, 230] grey levels, seeded.
cv::Mat make_scene() {
  cv::Mat noise(kHeight, kWidth + kDisparityPx, CV_32F);
  cv::RNG rng(17);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::normalize(noise, noise, 20.0, 230.0, cv::NORM_MINMAX);
  return noise;
}

// left(x) = scene(x); right(x) = scene(x + d) through the inverse of left = gain x right + offset, both
// rounded and saturated to 8 bit.
void make_pair(double gain, double offset, cv::Mat& left, cv::Mat& right) {
  const cv::Mat scene = make_scene();
  scene(cv::Rect(0, 0, kWidth, kHeight)).convertTo(left, CV_8U);
  cv::Mat shifted = scene(cv::Rect(kDisparityPx, 0, kWidth, kHeight));
  shifted.convertTo(right, CV_8U, 1.0 / gain, -offset / gain);
}

// Stereo matches on a grid: left (u, v), right (u - d, v).
StereoFeatures grid_matches() {
  StereoFeatures features;
  for (int v = 10; v < kHeight - 10; v += 8) {
    for (int u = 10 + kDisparityPx; u < kWidth - 10; u += 8) {
      Keypoint keypoint;
      keypoint.u_px = static_cast<float>(u);
      keypoint.v_px = static_cast<float>(v);
      features.keypoints.push_back(keypoint);
      features.descriptors.push_back(Descriptor{});
      features.u_right_px.push_back(static_cast<float>(u - kDisparityPx));
      features.depth_m.push_back(5.f);
    }
  }
  return features;
}

TEST(StereoTone, MeasuresAKnownGainAndOffset) {
  for (const auto& [gain, offset] : {std::pair{0.5, 6.0}, std::pair{4.0, -10.0}, std::pair{1.0, 0.0}}) {
    cv::Mat left;
    cv::Mat right;
    make_pair(gain, offset, left, right);
    const StereoToneMeasurement measured = measure_stereo_tone(left, right, grid_matches());
    ASSERT_TRUE(measured.valid) << "gain " << gain;
    EXPECT_NEAR(measured.tone.gain, gain, 0.03 * gain) << "gain " << gain;
    EXPECT_NEAR(measured.tone.offset, offset, 2.0) << "gain " << gain;
  }
}

TEST(StereoTone, LeavesOutClippedPatchesAndNeedsEnoughMatches) {
  cv::Mat left;
  cv::Mat right;
  make_pair(0.5, 0.0, left, right);  // right = 2 x left: saturated wherever the left passes 127
  const StereoFeatures features = grid_matches();
  const StereoToneMeasurement measured = measure_stereo_tone(left, right, features);
  ASSERT_TRUE(measured.valid);
  EXPECT_LT(measured.matches, static_cast<int>(features.size()) * 3 / 4);
  EXPECT_NEAR(measured.tone.gain, 0.5, 0.03 * 0.5);

  StereoToneMeasureOptions strict;
  strict.min_matches = static_cast<int>(features.size()) + 1;
  EXPECT_FALSE(measure_stereo_tone(left, right, features, strict).valid);
  EXPECT_THROW(measure_stereo_tone(left, cv::Mat(10, 10, CV_8UC1), features), std::invalid_argument);
}

StereoToneMeasurement measurement(double gain, bool valid = true) {
  StereoToneMeasurement m;
  m.valid = valid;
  m.tone.gain = gain;
  m.matches = valid ? 100 : 0;
  return m;
}

TEST(StereoTone, TrackerTakesTheMedianOfRecentMeasurements) {
  StereoToneTracker tracker;
  const LinearTone histograms{2.0, 0.0};
  EXPECT_FALSE(tracker.predict(histograms));
  for (double gain : {3.9, 4.3, 4.0, 3.7, 4.1}) tracker.update(measurement(gain), histograms);
  ASSERT_TRUE(tracker.predict(histograms));
  EXPECT_DOUBLE_EQ(tracker.predict(histograms)->gain, 4.0);
  tracker.update(measurement(4.2), histograms);  // the oldest (3.9) leaves the window of five
  EXPECT_DOUBLE_EQ(tracker.predict(histograms)->gain, 4.1);
  tracker.reset();
  EXPECT_FALSE(tracker.predict(histograms));
}

TEST(StereoTone, TrackerForgetsOldMeasurements) {
  StereoToneTrackerOptions options;
  options.max_age_pairs = 3;
  StereoToneTracker tracker(options);
  const LinearTone histograms{2.0, 0.0};
  tracker.update(measurement(4.0), histograms);
  for (int i = 0; i < 2; ++i) tracker.update(measurement(0.0, false), histograms);
  EXPECT_TRUE(tracker.predict(histograms));
  tracker.update(measurement(0.0, false), histograms);
  EXPECT_FALSE(tracker.predict(histograms));
}

TEST(StereoTone, TrackerFallsBackAtAnExposureStepSeenInTheHistograms) {
  StereoToneTracker tracker;
  for (int i = 0; i < 5; ++i) tracker.update(measurement(4.0), LinearTone{2.0, 0.0});
  // A small change of the histograms' fit is their noise: the measurements stand.
  EXPECT_DOUBLE_EQ(tracker.predict(LinearTone{2.2, 0.0})->gain, 4.0);
  // A step (x2 here): the quantile curve for that pair, and the measurements before it are dropped.
  EXPECT_FALSE(tracker.predict(LinearTone{4.0, 0.0}));
  tracker.update(measurement(7.6), LinearTone{4.0, 0.0});
  EXPECT_DOUBLE_EQ(tracker.predict(LinearTone{4.0, 0.0})->gain, 7.6);
}

TEST(StereoTone, TrackerDoesNotFollowAMeasurementFarFromTheRecentOnes) {
  StereoToneTracker tracker;
  const LinearTone histograms{2.0, 0.0};
  for (int i = 0; i < 3; ++i) tracker.update(measurement(0.25), histograms);
  tracker.update(measurement(0.6), histograms);  // x2.4: not trusted, and the rest dropped
  EXPECT_FALSE(tracker.predict(histograms));
  tracker.update(measurement(0.26), histograms);  // measured afresh on the quantile curve's pair
  EXPECT_DOUBLE_EQ(tracker.predict(histograms)->gain, 0.26);
}

// Real pairs: the relation of the exposed-apart copies against the equally exposed pair's own.
TEST(StereoTone, Mh01GainPairsMeasureTheirGainRatio) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  PinholeStereo camera;
  const std::vector<test::RectifiedPair> pairs = test::load_euroc_pairs({20, 60, 100, 140}, &camera);
  StereoFeaturePipelineOptions options;
  options.parallel = false;
  for (const auto& [left_gain, right_gain] : {std::pair{4.0, 1.0}, std::pair{0.35, 2.0}}) {
    double ratio_sum = 0.0;
    for (const test::RectifiedPair& pair : pairs) {
      StereoFeaturePipeline pipeline(camera, options);
      const StereoFeatures equal = pipeline.process(pair.left, pair.right);
      const StereoToneMeasurement reference = measure_stereo_tone(pair.left, pair.right, equal);
      cv::Mat left;
      cv::Mat right;
      pair.left.convertTo(left, CV_8U, left_gain);
      pair.right.convertTo(right, CV_8U, right_gain);
      StereoFeaturePipeline apart_pipeline(camera, options);
      const StereoToneMeasurement apart = measure_stereo_tone(left, right, apart_pipeline.process(left, right));
      ASSERT_TRUE(reference.valid && apart.valid);
      ratio_sum += apart.tone.gain / reference.tone.gain;
    }
    const double ratio = ratio_sum / static_cast<double>(pairs.size());
    std::printf("[ figures  ] left x%.2f / right x%.2f: measured gain %.4f of the equal pair's, %.4f expected\n",
                left_gain, right_gain, ratio, left_gain / right_gain);
    EXPECT_NEAR(ratio, left_gain / right_gain, 0.08 * left_gain / right_gain);
  }
}

}  // namespace
}  // namespace heslam

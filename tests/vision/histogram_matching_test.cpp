// Histogram matching: the identity for equal histograms, a known answer on a two-level image, a
// camera's monotonic tone change (gain, gamma, clipping) undone on a real texture, and the common
// range of a pair whose right camera clips much of the scene.
#include <cmath>

#include <gtest/gtest.h>

#include "components/core/image/histogram_matching.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

GreyHistogram histogram_of(const cv::Mat& image) {
  GreyHistogram h{};
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) ++h[image.at<std::uint8_t>(y, x)];
  }
  return h;
}

TEST(HistogramMatching, EqualHistogramsGiveTheIdentity) {
  HESLAM_REQUIRE_TEXTURE();
  const GreyHistogram h = histogram_of(test::load_texture());
  const GreyLut lut = match_histogram(h, h);
  for (int v = 0; v < 256; ++v) {
    if (h[v] > 0) {  // levels the image does not hold may go anywhere
      EXPECT_EQ(lut[v], v) << "level " << v;
    }
  }
  const GreyLut empty = match_histogram(GreyHistogram{}, h);
  for (int v = 0; v < 256; ++v) EXPECT_EQ(empty[v], v) << "level " << v;
}

TEST(HistogramMatching, TwoLevelsMapToTheReferenceQuantiles) {
  // Source: half 100, half 200. Reference: a quarter each of 10, 20, 30, 40. Level 100 sits at
  // quantile 0.25 (middle of its step), the top of the reference's level 10 -> 10.5 -> rounds to 11;
  // level 200 at 0.75, the top of level 30 -> 30.5 -> 31. Levels in between map in between.
  GreyHistogram source{};
  source[100] = 50;
  source[200] = 50;
  GreyHistogram reference{};
  for (int v : {10, 20, 30, 40}) reference[v] = 25;
  const GreyLut lut = match_histogram(source, reference);
  EXPECT_EQ(lut[100], 11);
  EXPECT_EQ(lut[200], 31);
  for (int v = 1; v < 256; ++v) EXPECT_GE(lut[v], lut[v - 1]) << "monotonic at " << v;
}

TEST(HistogramMatching, UndoesAMonotonicToneChangeOfTheOtherCamera) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat left = test::load_texture();
  // The "right camera": x0.35 and a gamma of 0.8, and separately x2 with the top clipped.
  for (const auto& [name, tone] :
       {std::pair{"dark gamma", +[](double v) { return 255.0 * std::pow(0.35 * v / 255.0, 0.8); }},
        std::pair{"bright clipped", +[](double v) { return 2.0 * v; }}}) {
    cv::Mat right(left.size(), CV_8UC1);
    for (int y = 0; y < left.rows; ++y) {
      for (int x = 0; x < left.cols; ++x) {
        right.at<std::uint8_t>(y, x) = cv::saturate_cast<std::uint8_t>(tone(left.at<std::uint8_t>(y, x)));
      }
    }
    const GreyLut lut = match_histogram(histogram_of(right), histogram_of(left));
    double error_sum = 0.0;
    int compared = 0;
    int before = 0;
    for (int y = 0; y < left.rows; ++y) {
      for (int x = 0; x < left.cols; ++x) {
        const int r = right.at<std::uint8_t>(y, x);
        if (r == 255) continue;  // clipped: nothing left to undo
        const int l = left.at<std::uint8_t>(y, x);
        error_sum += std::abs(static_cast<int>(lut[r]) - l);
        before += std::abs(r - l);
        ++compared;
      }
    }
    const double mean_error = error_sum / compared;
    std::printf("%s: mean |matched right - left| %.2f grey levels (before %.1f) over %d pixels\n", name, mean_error,
                static_cast<double>(before) / compared, compared);
    // Quantization of the compressed levels only (x0.35 leaves ~3 input levels per output level).
    EXPECT_LT(mean_error, 1.5) << name;
  }
}

TEST(HistogramMatching, ARightCameraThatClipsClipsTheLeftAtTheSameQuantile) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat left = test::load_texture();
  cv::Mat right;
  left.convertTo(right, CV_8U, 4.0);  // everything above grey 64 saturates
  const GreyHistogram left_histogram = histogram_of(left);
  const GreyHistogram right_histogram = histogram_of(right);
  const double saturated = static_cast<double>(right_histogram[255]) / static_cast<double>(right.total());
  ASSERT_GT(saturated, 0.3);
  const StereoToneCurves curves = align_stereo_tones(left_histogram, right_histogram, 0.1);
  ASSERT_TRUE(curves.left_clipped);
  // Pixel by pixel: where the right saturates, both are mapped to one level; elsewhere they agree
  // to the quantization of the x4 levels.
  int disagree = 0;
  for (int y = 0; y < left.rows; ++y) {
    for (int x = 0; x < left.cols; ++x) {
      const int l = curves.left[left.at<std::uint8_t>(y, x)];
      const int r = curves.right[right.at<std::uint8_t>(y, x)];
      disagree += std::abs(l - r) > 1 ? 1 : 0;
    }
  }
  EXPECT_LT(disagree, static_cast<int>(left.total() / 100)) << "pixels more than one level apart";
  // The left keeps its levels below the ceiling.
  const int ceiling = curves.right[255];
  EXPECT_GE(ceiling, 60);
  EXPECT_LE(ceiling, 66);
  for (int v = 0; v < ceiling; ++v) EXPECT_EQ(curves.left[v], v);

  // Equal exposure: no clipping of the left, the identity on both sides.
  const StereoToneCurves same = align_stereo_tones(left_histogram, left_histogram, 0.1);
  EXPECT_FALSE(same.left_clipped);
  EXPECT_EQ(same.mean_right_shift, 0.0);
  for (int v = 0; v < 256; ++v) EXPECT_EQ(same.left[v], v);
}

}  // namespace
}  // namespace heslam

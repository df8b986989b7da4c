// Histogram equalization: the paper's mapping as a known answer, one mapping for both images of a
// pair, CLAHE with shared tile LUTs, adaptive switching with hysteresis, options from YAML, the
// HE-SLAM claim on real EuRoC frames made dark or flat, and pairs whose cameras are exposed apart
// (matched / separate mappings); the split form (each image on its own thread) against the one-call
// form.
#include <numeric>
#include <string>
#include <thread>
#include <tuple>
#include <utility>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "components/core/image/histogram_equalizer.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

HistogramEqualizerOptions with_mode(HeMode mode, StereoPhotometry stereo = StereoPhotometry::kShared) {
  HistogramEqualizerOptions o;
  o.mode = mode;
  o.stereo = stereo;
  return o;
}

TEST(HistogramEqualizer, GlobalIsTheCdfOfTheJointHistogram) {
  // Left: half 10, half 20. Right: all 30. Joint histogram: 25 % 10, 25 % 20, 50 % 30, so the paper's
  // mapping y = 255 cdf(x) gives 10 -> 64, 20 -> 128, 30 -> 255.
  cv::Mat left(4, 8, CV_8UC1, cv::Scalar(10));
  left.colRange(4, 8).setTo(20);
  const cv::Mat right(4, 8, CV_8UC1, cv::Scalar(30));
  HistogramEqualizer equalizer(with_mode(HeMode::kGlobal));
  cv::Mat left_out, right_out;
  equalizer.equalize(left, right, left_out, right_out);
  EXPECT_EQ(left_out.at<std::uint8_t>(0, 0), 64);
  EXPECT_EQ(left_out.at<std::uint8_t>(0, 7), 128);
  EXPECT_EQ(right_out.at<std::uint8_t>(3, 3), 255);
  EXPECT_TRUE(equalizer.active());
}

TEST(HistogramEqualizer, ClippedLimitsTheStretchOfDominantLevels) {
  // Left: all 10; right: half 20, half 30 (512 pixels, mean bin 2). Global HE maps 10 -> 128,
  // 20 -> 191, 30 -> 255. Clipped at 2 x mean = 4 per bin: the excess 500 is spread as 1 to every bin
  // and 1 more to bins 0..243, so the three levels hold 6 each and the cdf gives 10 -> 13, 20 -> 25,
  // 30 -> 37 (y = (255 cdf + n/2) / n).
  const cv::Mat left(16, 16, CV_8UC1, cv::Scalar(10));
  cv::Mat right(16, 16, CV_8UC1, cv::Scalar(20));
  right.rowRange(8, 16).setTo(30);
  HistogramEqualizerOptions options = with_mode(HeMode::kClipped);
  options.global_clip_limit = 2.0;
  cv::Mat left_out, right_out;
  HistogramEqualizer equalizer(options);
  equalizer.equalize(left, right, left_out, right_out);
  EXPECT_EQ(left_out.at<std::uint8_t>(0, 0), 13);
  EXPECT_EQ(right_out.at<std::uint8_t>(0, 0), 25);
  EXPECT_EQ(right_out.at<std::uint8_t>(15, 15), 37);
  EXPECT_TRUE(equalizer.active());

  // A clip limit above every bin leaves the paper's global mapping.
  options.global_clip_limit = 1000.0;
  cv::Mat global_left, global_right;
  HistogramEqualizer(with_mode(HeMode::kGlobal)).equalize(left, right, global_left, global_right);
  HistogramEqualizer(options).equalize(left, right, left_out, right_out);
  EXPECT_EQ(cv::norm(left_out, global_left, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(right_out, global_right, cv::NORM_INF), 0.0);
  EXPECT_EQ(global_left.at<std::uint8_t>(0, 0), 128);
}

TEST(HistogramEqualizer, BothImagesGetTheSameMapping) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = test::load_texture();
  const cv::Mat left = texture(cv::Rect(0, 0, 400, 300)).clone();
  cv::Mat right = texture(cv::Rect(200, 200, 400, 300)).clone();
  for (const HeMode mode : {HeMode::kGlobal, HeMode::kClipped, HeMode::kClahe}) {
    cv::Mat left_out, right_out;
    HistogramEqualizer(with_mode(mode)).equalize(left, right, left_out, right_out);
    // Same input value at the same pixel position -> same output value in both images.
    int compared = 0;
    for (int y = 0; y < left.rows; y += 3) {
      for (int x = 0; x < left.cols; x += 3) {
        if (left.at<std::uint8_t>(y, x) != right.at<std::uint8_t>(y, x)) continue;
        ++compared;
        ASSERT_EQ(left_out.at<std::uint8_t>(y, x), right_out.at<std::uint8_t>(y, x)) << to_string(mode);
      }
    }
    EXPECT_GT(compared, 50) << to_string(mode);
    // Equalization spreads the histogram: the output's contrast is higher.
    cv::Scalar mean_in, sd_in, mean_out, sd_out;
    cv::meanStdDev(left, mean_in, sd_in);
    cv::meanStdDev(left_out, mean_out, sd_out);
    EXPECT_GT(sd_out[0], sd_in[0]) << to_string(mode);
  }
}

TEST(HistogramEqualizer, ClaheLimitsLocalContrastGain) {
  // A flat tile with tiny noise: global HE blows the noise up to full range, CLAHE's clip limit
  // keeps the gain bounded.
  cv::Mat flat(240, 320, CV_8UC1);
  cv::RNG rng(5);
  rng.fill(flat, cv::RNG::NORMAL, 128, 2);
  cv::Mat global_out, clahe_out, unused;
  HistogramEqualizer(with_mode(HeMode::kGlobal)).equalize(flat, flat, global_out, unused);
  HistogramEqualizer(with_mode(HeMode::kClahe)).equalize(flat, flat, clahe_out, unused);
  cv::Scalar mean, sd_global, sd_clahe;
  cv::meanStdDev(global_out, mean, sd_global);
  cv::meanStdDev(clahe_out, mean, sd_clahe);
  EXPECT_GT(sd_global[0], 50.0);
  EXPECT_LT(sd_clahe[0], 0.5 * sd_global[0]);
  // Same order of gain as OpenCV's CLAHE with the same clip limit and tiles.
  cv::Mat reference;
  cv::createCLAHE(2.0, cv::Size(8, 8))->apply(flat, reference);
  cv::Scalar sd_reference;
  cv::meanStdDev(reference, mean, sd_reference);
  std::printf("noise sigma 2 -> global HE %.1f, CLAHE %.1f, cv::CLAHE %.1f\n", sd_global[0], sd_clahe[0],
              sd_reference[0]);
  EXPECT_NEAR(sd_clahe[0], sd_reference[0], 0.25 * sd_reference[0]);
}

TEST(HistogramEqualizer, AdaptiveSwitchesWithHysteresis) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = test::load_texture()(cv::Rect(0, 0, 320, 240)).clone();
  cv::Scalar mean, sd;
  cv::meanStdDev(texture, mean, sd);
  // Contrast (standard deviation) scaled to chosen values around the thresholds 25 / 35.
  auto with_contrast = [&](double target) {
    cv::Mat out;
    texture.convertTo(out, CV_8U, target / sd[0], 128.0 - mean[0] * target / sd[0]);
    return out;
  };
  HistogramEqualizer equalizer(with_mode(HeMode::kAdaptive));
  const std::vector<std::pair<double, bool>> sequence = {{60, false}, {30, false}, {20, true},  {30, true},
                                                         {34, true},  {40, false}, {30, false}, {10, true}};
  for (const auto& [contrast, expect_active] : sequence) {
    const cv::Mat image = with_contrast(contrast);
    cv::Mat left_out, right_out;
    equalizer.equalize(image, image, left_out, right_out);
    EXPECT_NEAR(equalizer.last_contrast(), contrast, 1.5);
    EXPECT_EQ(equalizer.active(), expect_active) << "contrast " << contrast;
    if (!expect_active) {
      EXPECT_EQ(cv::norm(left_out, image, cv::NORM_INF), 0.0);
    }
  }
}

TEST(HistogramEqualizer, OptionsFromYaml) {
  const std::string text =
      "%YAML:1.0\nHE.mode: clahe\nHE.stereo: separate\nHE.clipLimit: 3.5\nHE.tilesX: 4\nHE.tilesY: "
      "3\nHE.adaptiveOnBelow: 10\n"
      "HE.adaptiveOffAbove: 20\n";
  cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  const HistogramEqualizerOptions o = HistogramEqualizerOptions::from_yaml(fs.root(), "test.yaml");
  EXPECT_EQ(o.mode, HeMode::kClahe);
  EXPECT_EQ(o.stereo, StereoPhotometry::kSeparate);
  EXPECT_EQ(o.clahe_clip_limit, 3.5);
  EXPECT_EQ(o.clahe_tiles_x, 4);
  EXPECT_EQ(o.clahe_tiles_y, 3);
  EXPECT_EQ(o.adaptive_on_below, 10.0);
  EXPECT_EQ(o.adaptive_off_above, 20.0);

  cv::FileStorage bad("%YAML:1.0\nHE.mode: sometimes\n", cv::FileStorage::READ | cv::FileStorage::MEMORY);
  try {
    HistogramEqualizerOptions::from_yaml(bad.root(), "bad.yaml");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml: HE.mode"), std::string::npos) << e.what();
  }
  cv::FileStorage bad_stereo("%YAML:1.0\nHE.stereo: both\n", cv::FileStorage::READ | cv::FileStorage::MEMORY);
  try {
    HistogramEqualizerOptions::from_yaml(bad_stereo.root(), "bad.yaml");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml: HE.stereo"), std::string::npos) << e.what();
  }
  cv::FileStorage inverted("%YAML:1.0\nHE.adaptiveOnBelow: 30\nHE.adaptiveOffAbove: 20\n",
                           cv::FileStorage::READ | cv::FileStorage::MEMORY);
  EXPECT_THROW(HistogramEqualizerOptions::from_yaml(inverted.root(), "x.yaml"), std::runtime_error);
}

// The matched photometry's thresholds are constants, not settings keys: a settings file giving one
// (the shipped files did before issue 33) changes nothing.
TEST(HistogramEqualizer, MatchedThresholdsAreNotSettingsKeys) {
  cv::FileStorage fs("%YAML:1.0\nHE.matchGainFrom: 2.5\nHE.matchShiftFrom: 10\nHE.saturationExcess: 0.5\n",
                     cv::FileStorage::READ | cv::FileStorage::MEMORY);
  EXPECT_TRUE(HistogramEqualizerOptions::from_yaml(fs.root(), "test.yaml") == HistogramEqualizerOptions{});
}

TEST(HistogramEqualizer, ADarkPairExposedApartIsRecognisedByItsGain) {
  // A dark texture (x0.1) seen at left x0.5 / right x1.5: the right's pixels move by only a few grey
  // levels, under match_shift_from, but the histograms' gain (~1/3) is beyond match_gain_from.
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = test::load_texture()(cv::Rect(0, 0, 400, 300)).clone();
  cv::Mat left, right;
  texture.convertTo(left, CV_8U, 0.1 * 0.5);
  texture.convertTo(right, CV_8U, 0.1 * 1.5);
  HistogramEqualizer equalizer(with_mode(HeMode::kClipped, StereoPhotometry::kMatched));
  cv::Mat left_out, right_out;
  equalizer.equalize(left, right, left_out, right_out);
  EXPECT_LT(equalizer.last_tone_shift(), equalizer.options().match_shift_from);
  EXPECT_NEAR(equalizer.last_histogram_tone().gain, 1.0 / 3.0, 0.1);
  EXPECT_TRUE(equalizer.last_exposed_apart());
  // The same dark texture on both cameras is not.
  equalizer.equalize(left, left, left_out, right_out);
  EXPECT_FALSE(equalizer.last_exposed_apart());
}

TEST(HistogramEqualizer, MatchedUndoesTheRightCameraGain) {
  // The same image seen by a left camera at x1 and a right camera at x2 (a third of it clipped).
  // Matched: wherever the right is not clipped both outputs agree (measured: exactly), in every HE
  // mode; shared (one mapping of the joint histogram) keeps them 71-89 grey levels apart.
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat left = test::load_texture()(cv::Rect(0, 0, 400, 300)).clone();
  cv::Mat right;
  left.convertTo(right, CV_8U, 2.0);
  auto mean_difference = [&](const cv::Mat& a, const cv::Mat& b) {
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < a.rows; ++y) {
      for (int x = 0; x < a.cols; ++x) {
        if (right.at<std::uint8_t>(y, x) == 255) continue;
        sum += std::abs(static_cast<int>(a.at<std::uint8_t>(y, x)) - b.at<std::uint8_t>(y, x));
        ++n;
      }
    }
    return sum / n;
  };
  for (const HeMode mode : {HeMode::kGlobal, HeMode::kClipped, HeMode::kClahe, HeMode::kAdaptive}) {
    cv::Mat left_out, right_out;
    HistogramEqualizer(with_mode(mode, StereoPhotometry::kMatched)).equalize(left, right, left_out, right_out);
    const double matched = mean_difference(left_out, right_out);
    HistogramEqualizer(with_mode(mode, StereoPhotometry::kShared)).equalize(left, right, left_out, right_out);
    const double shared = mean_difference(left_out, right_out);
    std::printf("%-8s right x2: mean |left - right| after HE: matched %.2f, shared %.1f grey levels\n", to_string(mode),
                matched, shared);
    EXPECT_LT(matched, 2.5) << to_string(mode);
    EXPECT_GT(shared, 10.0) << to_string(mode);
  }
}

TEST(HistogramEqualizer, MatchedLeavesEqualExposureAlmostUnchanged) {
  // Same histograms (here: the same image twice): the matching curve is the identity, so matched
  // gives exactly what shared gives.
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat image = test::load_texture()(cv::Rect(0, 0, 400, 300)).clone();
  for (const HeMode mode : {HeMode::kGlobal, HeMode::kClipped, HeMode::kClahe}) {
    cv::Mat matched_left, matched_right, shared_left, shared_right;
    HistogramEqualizer(with_mode(mode, StereoPhotometry::kMatched)).equalize(image, image, matched_left, matched_right);
    HistogramEqualizer(with_mode(mode, StereoPhotometry::kShared)).equalize(image, image, shared_left, shared_right);
    EXPECT_EQ(cv::norm(matched_left, shared_left, cv::NORM_INF), 0.0) << to_string(mode);
    EXPECT_EQ(cv::norm(matched_right, shared_right, cv::NORM_INF), 0.0) << to_string(mode);
  }
}

// Features and stereo matches of a list of pairs under one pipeline configuration.
struct Counts {
  std::size_t features = 0;
  std::size_t stereo = 0;
};

Counts count(const PinholeStereo& camera, HeMode mode, const std::vector<test::RectifiedPair>& pairs,
             StereoPhotometry stereo = HistogramEqualizerOptions{}.stereo) {
  StereoFeaturePipelineOptions options;
  options.he.mode = mode;
  options.he.stereo = stereo;
  StereoFeaturePipeline pipeline(camera, options);
  Counts c;
  for (const auto& pair : pairs) {
    const StereoFeatures f = pipeline.process(pair.left, pair.right);
    c.features += f.size();
    for (std::size_t i = 0; i < f.size(); ++i) c.stereo += f.has_stereo(i) ? 1 : 0;
  }
  return c;
}

TEST(HistogramEqualizer, DarkAndFlatEurocFramesKeepTheirFeatures) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  PinholeStereo camera;
  const auto original = test::load_euroc_pairs({0, 60, 120}, &camera);
  cv::RNG rng(2023);                   // seeded: the same noise every run
  constexpr double kNoiseSigma = 1.0;  // grey levels, sensor read noise on the dark frames
  auto degrade = [&](const cv::Mat& image, bool dark) {
    cv::Mat f;
    image.convertTo(f, CV_32F);
    if (dark) {
      cv::Mat noise(image.size(), CV_32F);
      rng.fill(noise, cv::RNG::NORMAL, 0.0, kNoiseSigma);
      f = f * 0.1 + noise;
    } else {
      f = (f - 128.0) * 0.12 + 128.0;
    }
    cv::Mat out;
    f.convertTo(out, CV_8U);  // rounds and saturates
    return out;
  };
  std::vector<test::RectifiedPair> dark, flat;
  for (const auto& p : original) {
    dark.push_back({degrade(p.left, true), degrade(p.right, true)});
    flat.push_back({degrade(p.left, false), degrade(p.right, false)});
  }
  std::printf("%-9s %-9s %9s %9s   (3 EuRoC MH01 pairs, 1200 features each)\n", "HE", "images", "features", "stereo");
  for (const HeMode mode : {HeMode::kNone, HeMode::kGlobal, HeMode::kClipped, HeMode::kAdaptive, HeMode::kClahe}) {
    const Counts base = count(camera, mode, original);
    std::printf("%-9s %-9s %9zu %9zu\n", to_string(mode), "original", base.features, base.stereo);
    for (const auto& [name, pairs] : {std::pair{"dark", &dark}, std::pair{"flat", &flat}}) {
      const Counts c = count(camera, mode, *pairs);
      std::printf("%-9s %-9s %9zu %9zu  (%3.0f %% / %3.0f %% of original)\n", to_string(mode), name, c.features,
                  c.stereo, 100.0 * c.features / base.features, 100.0 * c.stereo / base.stereo);
      if (mode == HeMode::kGlobal || mode == HeMode::kClipped || mode == HeMode::kAdaptive) {
        EXPECT_GE(c.features, 0.8 * base.features) << to_string(mode) << " " << name;
        EXPECT_GE(c.stereo, 0.8 * base.stereo) << to_string(mode) << " " << name;
      }
    }
  }
}

// Real EuRoC pairs whose cameras are exposed apart (left x0.35, right x2 and clipped; left x1, right
// x4, 40-58 % of it saturated): with the shared mapping stereo matching loses half its matches, with
// the matched one it keeps them.
TEST(HistogramEqualizer, EurocPairsExposedApartKeepTheirStereoMatches) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  PinholeStereo camera;
  const auto original = test::load_euroc_pairs({0, 60, 120}, &camera);
  auto with_gains = [&](double left_gain, double right_gain) {
    std::vector<test::RectifiedPair> pairs;
    for (const auto& p : original) {
      test::RectifiedPair q;
      p.left.convertTo(q.left, CV_8U, left_gain);  // rounds and saturates
      p.right.convertTo(q.right, CV_8U, right_gain);
      pairs.push_back(q);
    }
    return pairs;
  };
  std::printf("%-9s %-9s %9s %9s %9s   (3 EuRoC MH01 pairs, clipped HE)\n", "stereo", "gains", "features", "stereo",
              "");
  for (const StereoPhotometry stereo :
       {StereoPhotometry::kShared, StereoPhotometry::kMatched, StereoPhotometry::kSeparate}) {
    const Counts base = count(camera, HeMode::kClipped, original, stereo);
    std::printf("%-9s %-9s %9zu %9zu\n", to_string(stereo), "1/1", base.features, base.stereo);
    for (const auto& [name, left_gain, right_gain] : {std::tuple{"0.35/2", 0.35, 2.0}, std::tuple{"1/4", 1.0, 4.0}}) {
      const Counts c = count(camera, HeMode::kClipped, with_gains(left_gain, right_gain), stereo);
      std::printf("%-9s %-9s %9zu %9zu  (%3.0f %% of the equal exposure's stereo)\n", to_string(stereo), name,
                  c.features, c.stereo, 100.0 * c.stereo / base.stereo);
      // Measured: shared 49 % / 44 %, matched 102 % / 94 % (the left clipped where the right is white,
      // so its features lie where both cameras see texture), separate 61 % / 50 %.
      if (stereo == StereoPhotometry::kMatched) {
        EXPECT_GE(c.features, 0.9 * base.features) << name;
        EXPECT_GE(c.stereo, 0.85 * base.stereo) << name;
      }
      if (stereo == StereoPhotometry::kShared) {
        EXPECT_LT(c.stereo, 0.7 * base.stereo) << name << ": the shared mapping's failure on cameras exposed apart";
      }
    }
  }
}

// The split form (each image measured and mapped on its own thread, the mappings computed once
// between) against the one-call equalizer, pixel for pixel, for every mode and stereo mode, on real
// MH01 pairs and on the same pairs with the cameras exposed apart or both made dark (adaptive
// switches on there); one equalizer of each form sees the whole sequence (adaptive keeps state).
TEST(HistogramEqualizer, SplitOnTwoThreadsGivesTheOneCallPixels) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  const auto original = test::load_euroc_pairs({0, 60, 120}, nullptr);
  std::vector<test::RectifiedPair> pairs;
  for (const auto& [left_gain, right_gain] :
       {std::pair{1.0, 1.0}, std::pair{0.35, 2.0}, std::pair{1.0, 4.0}, std::pair{0.1, 0.1}, std::pair{1.0, 1.0}}) {
    for (const auto& p : original) {
      test::RectifiedPair q;
      p.left.convertTo(q.left, CV_8U, left_gain);  // rounds and saturates
      p.right.convertTo(q.right, CV_8U, right_gain);
      pairs.push_back(q);
    }
  }
  using Side = HistogramEqualizer::Side;
  for (const HeMode mode : {HeMode::kNone, HeMode::kGlobal, HeMode::kClipped, HeMode::kClahe, HeMode::kAdaptive}) {
    for (const StereoPhotometry stereo :
         {StereoPhotometry::kShared, StereoPhotometry::kMatched, StereoPhotometry::kSeparate}) {
      HistogramEqualizer one_call(with_mode(mode, stereo));
      HistogramEqualizer split(with_mode(mode, stereo));
      cv::Mat left_buffer, right_buffer;
      int switched_on = 0;
      for (std::size_t p = 0; p < pairs.size(); ++p) {
        const std::string where = std::string(to_string(mode)) + "/" + to_string(stereo) + " pair " + std::to_string(p);
        cv::Mat left_expected, right_expected;
        one_call.equalize(pairs[p].left, pairs[p].right, left_expected, right_expected);

        const cv::Mat* right_out = nullptr;
        std::thread right_thread([&] { split.add_histogram(Side::kRight, pairs[p].right); });
        split.add_histogram(Side::kLeft, pairs[p].left);
        right_thread.join();
        split.compute_mappings();
        right_thread = std::thread([&] { right_out = &split.apply(Side::kRight, pairs[p].right, right_buffer); });
        const cv::Mat& left_out = split.apply(Side::kLeft, pairs[p].left, left_buffer);
        right_thread.join();

        ASSERT_EQ(left_out.size(), left_expected.size()) << where;
        ASSERT_EQ(right_out->size(), right_expected.size()) << where;
        EXPECT_EQ(cv::countNonZero(left_out != left_expected), 0) << where;
        EXPECT_EQ(cv::countNonZero(*right_out != right_expected), 0) << where;
        EXPECT_EQ(split.active(), one_call.active()) << where;
        EXPECT_EQ(split.last_contrast(), one_call.last_contrast()) << where;
        EXPECT_EQ(split.last_tone_shift(), one_call.last_tone_shift()) << where;
        // Unchanged images are passed through, not copied; the caller's images are never written.
        const bool unchanged = mode == HeMode::kNone ||
                               (mode == HeMode::kAdaptive && !split.active() && stereo != StereoPhotometry::kMatched);
        EXPECT_EQ(&left_out == &pairs[p].left, unchanged) << where;
        EXPECT_EQ(right_out == &pairs[p].right, unchanged) << where;
        switched_on += mode == HeMode::kAdaptive && split.active() ? 1 : 0;
      }
      if (mode == HeMode::kAdaptive) {
        EXPECT_GT(switched_on, 0) << "the dark pairs switch adaptive HE on";
      }
    }
  }
  // The one-call equalizer's input images are left as they were (the split form wrote its buffers).
  const auto fresh = test::load_euroc_pairs({0}, nullptr);
  EXPECT_EQ(cv::countNonZero(pairs[0].left != fresh[0].left), 0);

  // Bad input: an image of another size than the one measured, or histograms of two sizes.
  HistogramEqualizer equalizer;
  cv::Mat buffer;
  equalizer.add_histogram(Side::kLeft, original[0].left);
  equalizer.add_histogram(Side::kRight, original[0].right.colRange(0, 100));
  EXPECT_THROW(equalizer.compute_mappings(), std::invalid_argument);
  equalizer.add_histogram(Side::kRight, original[0].right);
  equalizer.compute_mappings();
  EXPECT_THROW(equalizer.apply(Side::kLeft, original[0].left.rowRange(0, 10), buffer), std::invalid_argument);
  EXPECT_THROW(equalizer.add_histogram(Side::kLeft, cv::Mat(4, 4, CV_16UC1)), std::invalid_argument);
}

}  // namespace
}  // namespace heslam

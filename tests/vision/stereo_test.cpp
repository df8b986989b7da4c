// Stereo matching: known depth on a synthetic scene (a real texture warped with the exact disparity
// of a slanted plane around 5 m seen by the EuRoC rig) and real rectified EuRoC pairs.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "components/core/feature/orb_extractor.hpp"
#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "components/core/match/descriptor_matcher.hpp"
#include "vision_test_data.hpp"

namespace heslam {
namespace {

PinholeStereo euroc_rig() {
  return StereoRectifier(load_orbslam_settings(test::source_dir() / "config" / "camera" / "EuRoC.yaml")).camera();
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
}

// A real texture seen as a plane whose depth goes from 5.5 m (top row) to 4.5 m (bottom row): for a
// plane 1/depth is affine in the image row, so disparity(v) = bf (a + b v) exactly, and the right
// image row v is the left row shifted by disparity(v).
struct SlantedPlane {
  static constexpr double kNearM = 4.5;
  static constexpr double kFarM = 5.5;
  PinholeStereo camera;
  cv::Mat left, right;

  double inverse_depth(double v) const {
    return 1.0 / kFarM + (1.0 / kNearM - 1.0 / kFarM) * v / (camera.height_px - 1);
  }
};

SlantedPlane render_slanted_plane(const cv::Mat& texture) {
  SlantedPlane plane{euroc_rig(), {}, {}};
  const PinholeStereo& camera = plane.camera;
  cv::Mat map_left_x(camera.height_px, camera.width_px, CV_32F);
  cv::Mat map_right_x(camera.height_px, camera.width_px, CV_32F);
  cv::Mat map_y(camera.height_px, camera.width_px, CV_32F);
  const double origin_x = 12.0;  // texture column of the left image's column 0
  for (int v = 0; v < camera.height_px; ++v) {
    const double disparity = camera.bf() * plane.inverse_depth(v);
    for (int u = 0; u < camera.width_px; ++u) {
      map_left_x.at<float>(v, u) = static_cast<float>(origin_x + u);
      // Right pixel u sees the scene point of left pixel u + disparity.
      map_right_x.at<float>(v, u) = static_cast<float>(origin_x + u + disparity);
      map_y.at<float>(v, u) = static_cast<float>(v);
    }
  }
  cv::Mat smooth;
  cv::GaussianBlur(texture, smooth, cv::Size(0, 0), 0.7);  // band-limit before resampling
  cv::remap(smooth, plane.left, map_left_x, map_y, cv::INTER_CUBIC, cv::BORDER_REFLECT_101);
  cv::remap(smooth, plane.right, map_right_x, map_y, cv::INTER_CUBIC, cv::BORDER_REFLECT_101);
  return plane;
}

struct PlaneFigures {
  double matched = 0.0;             // share of left keypoints with depth
  double depth_error_median = 1.0;  // relative
  double depth_error_p90 = 1.0;
  double disparity_error_median_px = 1e9;
};

PlaneFigures measure_plane(const SlantedPlane& plane, const cv::Mat& left, const cv::Mat& right,
                           const StereoFeaturePipelineOptions& options, const char* label) {
  StereoFeaturePipeline pipeline(plane.camera, options);
  const StereoFeatures features = pipeline.process(left, right);
  std::vector<double> relative_error;
  std::vector<double> disparity_error_px;
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!features.has_stereo(i)) continue;
    const double true_depth = 1.0 / plane.inverse_depth(features.keypoints[i].v_px);
    relative_error.push_back(std::abs(features.depth_m[i] - true_depth) / true_depth);
    disparity_error_px.push_back(
        std::abs(features.keypoints[i].u_px - features.u_right_px[i] - plane.camera.bf() / true_depth));
  }
  PlaneFigures f;
  if (relative_error.empty()) return f;
  f.matched = static_cast<double>(relative_error.size()) / static_cast<double>(features.size());
  f.depth_error_median = median(relative_error);
  f.depth_error_p90 = percentile(relative_error, 0.9);
  f.disparity_error_median_px = median(disparity_error_px);
  std::printf(
      "%s: %zu of %zu keypoints matched (%.0f %%), depth error median %.3f %% (90th pct %.3f %%), "
      "disparity error median %.3f px\n",
      label, relative_error.size(), features.size(), 100 * f.matched, 100 * f.depth_error_median,
      100 * f.depth_error_p90, f.disparity_error_median_px);
  return f;
}

TEST(StereoMatcher, KnownDepthOfASlantedPlaneAround5m) {
  HESLAM_REQUIRE_TEXTURE();
  const cv::Mat texture = test::load_texture();
  ASSERT_GE(texture.cols, euroc_rig().width_px + 24);
  ASSERT_GE(texture.rows, euroc_rig().height_px);
  const SlantedPlane plane = render_slanted_plane(texture);
  const PlaneFigures f = measure_plane(plane, plane.left, plane.right, {}, "synthetic plane 4.5-5.5 m");
  EXPECT_GT(f.matched, 0.5);
  EXPECT_LT(f.depth_error_median, 0.01);
}

TEST(StereoMatcher, RealEurocPairsMatchOnTheSameRow) {
  HESLAM_REQUIRE_SHARED_DATA(test::kEurocDataset);
  PinholeStereo camera;
  const auto pairs = test::load_euroc_pairs({0, 60, 120}, &camera);
  // The paper's global HE, which these thresholds were measured with. The default clipped HE keeps
  // fewer weak-texture corners: pair 60 has 49 % stereo with it (docs/vision.md).
  StereoFeaturePipelineOptions options;
  options.he.mode = HeMode::kGlobal;
  StereoFeaturePipeline pipeline(camera, options);
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const StereoFeatures features = pipeline.process(pairs[p].left, pairs[p].right);
    std::size_t stereo = 0;
    for (std::size_t i = 0; i < features.size(); ++i) stereo += features.has_stereo(i) ? 1 : 0;

    // Rectification check independent of the stereo matcher's row band: match left and right
    // features over the whole image by descriptor and measure the row difference of the matches.
    cv::Mat left_he, right_he;
    HistogramEqualizer(options.he).equalize(pairs[p].left, pairs[p].right, left_he, right_he);
    OrbFeatures left, right;
    OrbExtractor().extract(left_he, left);
    OrbExtractor().extract(right_he, right);
    std::vector<double> row_error_px;
    for (const DescriptorMatch& m : DescriptorMatcher().match(left.descriptors, right.descriptors)) {
      const Keypoint& kl = left.keypoints[static_cast<std::size_t>(m.query)];
      const Keypoint& kr = right.keypoints[static_cast<std::size_t>(m.train)];
      const double disparity = kl.u_px - kr.u_px;
      // Levels 0 and 1 only, in pixels of the keypoint's level (a corner's position is known to
      // one pixel of the level it was detected on: 1.2 px on level 1).
      if (kl.octave > 1 || kr.octave != kl.octave || disparity < 0.0 || disparity > camera.fx_px) continue;
      row_error_px.push_back(std::abs(kl.v_px - kr.v_px) / (kl.octave == 0 ? 1.0 : 1.2));
    }
    ASSERT_GT(row_error_px.size(), 30u);
    // Unconstrained descriptor matching has some gross mismatches with any row error; a bad
    // rectification would instead shift the rows of all matches. Rows within 8 px are "near".
    constexpr double kNearRowPx = 8.0;
    std::vector<double> near;
    for (double e : row_error_px) {
      if (e <= kNearRowPx) near.push_back(e);
    }
    const double near_share = static_cast<double>(near.size()) / static_cast<double>(row_error_px.size());
    const double within_1px =
        static_cast<double>(std::count_if(near.begin(), near.end(), [](double e) { return e <= 1.0 + 1e-4; })) /
        static_cast<double>(near.size());
    std::printf(
        "EuRoC pair %zu: %zu of %zu left features have stereo (%.0f %%); unconstrained level-0/1 matches: "
        "%zu, %.0f %% within %.0f px of the row, of those: median row error %.2f px, %.0f %% within 1 (level) px\n",
        p, stereo, features.size(), 100.0 * stereo / features.size(), row_error_px.size(), 100 * near_share, kNearRowPx,
        median(near), 100 * within_1px);
    EXPECT_GT(stereo, features.size() / 2);
    EXPECT_GE(near_share, 0.8);
    EXPECT_LE(median(near), 0.5);
    EXPECT_GE(within_1px, 0.95);
  }
}

TEST(StereoFeaturePipeline, ParallelEqualsSerial) {
  HESLAM_REQUIRE_TEXTURE();
  const PinholeStereo camera = euroc_rig();
  const cv::Mat texture = test::load_texture();
  const cv::Mat left = texture(cv::Rect(20, 0, camera.width_px, camera.height_px)).clone();
  const cv::Mat right = texture(cv::Rect(10, 0, camera.width_px, camera.height_px)).clone();
  StereoFeaturePipelineOptions serial_options;
  serial_options.parallel = false;
  StereoFeaturePipeline serial(camera, serial_options);
  StereoFeaturePipeline parallel(camera, StereoFeaturePipelineOptions{});
  StereoFeatureTimings timings;
  const StereoFeatures a = serial.process(left, right);
  parallel.process(right, left);  // a different pair in between: buffers are reused
  const StereoFeatures b = parallel.process(left, right, &timings);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.u_right_px.size(), a.size());
  ASSERT_EQ(a.depth_m.size(), a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].u_px, b.keypoints[i].u_px);
    EXPECT_EQ(a.descriptors[i], b.descriptors[i]);
    EXPECT_EQ(a.u_right_px[i], b.u_right_px[i]);
    EXPECT_EQ(a.depth_m[i], b.depth_m[i]);
  }
  EXPECT_GE(timings.total_ms, timings.extract_ms);
  EXPECT_THROW(parallel.process(left.colRange(0, 100), right), std::invalid_argument);
}

// process_from (each image made, measured, mapped and turned into its pyramid on its own thread)
// gives what process() gives on the made images, parallel or not; a source's error reaches the
// caller, a made image of the wrong size is refused, and the pipeline goes on afterwards.
TEST(StereoFeaturePipeline, ProcessFromEqualsProcess) {
  HESLAM_REQUIRE_TEXTURE();
  const PinholeStereo camera = euroc_rig();
  const cv::Mat texture = test::load_texture();
  const cv::Mat left = texture(cv::Rect(20, 0, camera.width_px, camera.height_px)).clone();
  const cv::Mat right = texture(cv::Rect(10, 0, camera.width_px, camera.height_px)).clone();
  for (const bool parallel : {true, false}) {
    for (const HeMode mode : {HeMode::kClipped, HeMode::kNone, HeMode::kClahe}) {
      StereoFeaturePipelineOptions options;
      options.parallel = parallel;
      options.he.mode = mode;
      StereoFeaturePipeline reference(camera, options);
      StereoFeaturePipeline pipeline(camera, options);
      cv::Mat left_made, right_made;
      auto make_left = [&]() -> const cv::Mat& {
        left.copyTo(left_made);
        return left_made;
      };
      auto make_right = [&]() -> const cv::Mat& {
        right.copyTo(right_made);
        return right_made;
      };
      StereoFeatureTimings timings;
      const StereoFeatures a = reference.process(left, right);
      pipeline.process(right, left);  // a different pair in between: buffers are reused
      const StereoFeatures b = pipeline.process_from(make_left, make_right, &timings);
      ASSERT_EQ(a.size(), b.size());
      for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a.keypoints[i].u_px, b.keypoints[i].u_px);
        EXPECT_EQ(a.descriptors[i], b.descriptors[i]);
        EXPECT_EQ(a.u_right_px[i], b.u_right_px[i]);
        EXPECT_EQ(a.depth_m[i], b.depth_m[i]);
      }
      EXPECT_GT(timings.source_ms, 0.0);
      EXPECT_GE(timings.total_ms, timings.extract_ms);
      EXPECT_EQ(cv::countNonZero(left_made != left), 0) << "the made image is not written";

      const cv::Mat small = left.colRange(0, 100);
      EXPECT_THROW(pipeline.process_from(make_left, [&]() -> const cv::Mat& { return small; }), std::invalid_argument);
      EXPECT_THROW(pipeline.process_from([]() -> const cv::Mat& { throw std::runtime_error("no image"); }, make_right),
                   std::runtime_error);
      const StereoFeatures c = pipeline.process_from(make_left, make_right);
      EXPECT_EQ(c.size(), a.size());
    }
  }
}

}  // namespace
}  // namespace heslam

namespace heslam {
namespace {

TEST(StereoFeaturePipeline, ShippedSettingsGiveTheDocumentedOptions) {
  const auto dir = test::source_dir() / "config" / "camera";
  const StereoFeaturePipelineOptions euroc = StereoFeaturePipelineOptions::load(dir / "EuRoC.yaml");
  EXPECT_EQ(euroc.orb.features, 1200);
  EXPECT_EQ(euroc.he.mode, HeMode::kClipped);
  EXPECT_EQ(euroc.stereo.max_distance, 100);
  EXPECT_EQ(euroc.right_features_factor, 2.f);
  EXPECT_EQ(euroc.left_only_features, 1.f);
  EXPECT_EQ(euroc.clip_edge.radius_px, 6);
  EXPECT_EQ(euroc.clip_edge.min_clipped_fraction, 0.01);
  for (const char* name : {"KITTI00-02.yaml", "KITTI03.yaml", "KITTI04-12.yaml"}) {
    const StereoFeaturePipelineOptions kitti = StereoFeaturePipelineOptions::load(dir / name);
    EXPECT_EQ(kitti.orb.features, 2000) << name;
    EXPECT_EQ(kitti.orb.levels, 8) << name;
    EXPECT_EQ(kitti.orb.fast_threshold_min, 7) << name;
    EXPECT_EQ(kitti.left_only_features, 1.f) << name;
  }
  // A bad value is one line naming the file and the key.
  const auto bad = std::filesystem::path(::testing::TempDir()) / "heslam_bad_pipeline.yaml";
  for (const auto& [key, value] : {std::pair{"ORBextractor.nFeatures", "many"},
                                   std::pair{"Pipeline.leftOnlyFeatures", "-1"}, std::pair{"Stereo.rowBand", "-1"}}) {
    std::ofstream(bad) << "%YAML:1.0\n" << key << ": " << value << "\n";
    try {
      StereoFeaturePipelineOptions::load(bad);
      ADD_FAILURE() << "expected an error for " << key;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("heslam_bad_pipeline.yaml: ") + key), std::string::npos)
          << e.what();
    }
  }
}

// Stereo.rowBand is the matcher's one settings key; its other options (ORB-SLAM2's constants and the
// SAD refinement measured here) are not read from a settings file, whatever it holds.
TEST(StereoMatcher, OnlyTheRowBandIsASettingsKey) {
  using Options = StereoMatcherOptions;
  cv::FileStorage fs(
      "%YAML:1.0\nStereo.rowBand: 3.0\nStereo.sadNormalization: none\nStereo.subpixelFit: spline\n"
      "Stereo.maxDistance: 90\n",
      cv::FileStorage::READ | cv::FileStorage::MEMORY);
  const Options o = Options::from_yaml(fs.root(), "test.yaml");
  const Options defaults;
  EXPECT_EQ(o.row_band_px, 3.f);
  EXPECT_EQ(o.sad_normalization, Options::SadNormalization::kMean);
  EXPECT_EQ(o.subpixel_fit, Options::SubpixelFit::kEquiangular);
  EXPECT_EQ(o.max_distance, defaults.max_distance);
  cv::FileStorage bad("%YAML:1.0\nStereo.rowBand: 0\n", cv::FileStorage::READ | cv::FileStorage::MEMORY);
  try {
    Options::from_yaml(bad.root(), "bad.yaml");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml: Stereo.rowBand"), std::string::npos) << e.what();
  }
}

// The SAD window and search range are code-only options; a value that would read past the margin the
// extractor keeps around each level is refused when the matcher is built, naming the field.
TEST(StereoMatcher, RefusesSadWindowsOutsideTheLevelMargin) {
  const ScalePyramid pyramid = ScalePyramid::make(8, 1.2f);
  const auto error_of = [&](StereoMatcherOptions options) -> std::string {
    try {
      StereoMatcher matcher(euroc_rig(), pyramid, options);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error_of({}), "");
  StereoMatcherOptions wide;
  wide.sad_half_window_px = 10;
  EXPECT_NE(error_of(wide).find("sad_half_window_px"), std::string::npos);
  StereoMatcherOptions none;
  none.sad_half_window_px = 0;
  EXPECT_NE(error_of(none).find("sad_half_window_px"), std::string::npos);
  StereoMatcherOptions narrow_search;
  narrow_search.sad_search_px = 1;
  EXPECT_NE(error_of(narrow_search).find("sad_search_px"), std::string::npos);
}

}  // namespace
}  // namespace heslam

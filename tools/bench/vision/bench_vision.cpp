// Timings of the vision core on a real EuRoC pair (752x480, 1200 features) and a KITTI-sized pair
// (1241x376, 2000 features, made by scaling and cropping the EuRoC pair): rectification, HE per mode,
// pyramid, FAST + distribution (+ orientation), descriptors, stereo matching, the whole pipeline
// single-threaded and left/right parallel, and cv::ORB for reference.
//
//   heslam-bench-vision [--benchmark_repetitions=9 --benchmark_report_aggregates_only=true]
// Needs ../shared/data/euroc_mh01_handheld (or HESLAM_BENCH_EUROC=<mav0 dir>). Environment
// HESLAM_BENCH_CV_THREADS=n sets OpenCV's thread count (default: OpenCV's choice).
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include <benchmark/benchmark.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/feature/orb_extractor.hpp"
#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "components/core/feature/stereo_tone.hpp"
#include "components/core/image/histogram_equalizer.hpp"
#include "components/core/image/histogram_matching.hpp"
#include "components/core/match/stereo_matcher.hpp"

namespace heslam {
namespace {

// The first frame of the clip: a typical machine-hall view.
constexpr const char* kFrame = "1403636584763555584.png";
constexpr int kKittiWidthPx = 1241;
constexpr int kKittiHeightPx = 376;
constexpr int kKittiFeatures = 2000;

struct Data {
  std::unique_ptr<StereoRectifier> rectifier;
  cv::Mat left_raw, right_raw;
  cv::Mat left, right;  // rectified
  PinholeStereo camera;
  cv::Mat kitti_left, kitti_right;
  PinholeStereo kitti_camera;
};

const Data& data() {
  static const Data d = [] {
    Data d;
    const char* env = std::getenv("HESLAM_BENCH_EUROC");
    const std::filesystem::path mav0 =
        env ? std::filesystem::path(env) : std::filesystem::path(HESLAM_SHARED_DATA) / "euroc_mh01_handheld" / "mav0";
    d.rectifier = std::make_unique<StereoRectifier>(load_euroc_calibration(mav0));
    d.left_raw = cv::imread((mav0 / "cam0" / "data" / kFrame).string(), cv::IMREAD_GRAYSCALE);
    d.right_raw = cv::imread((mav0 / "cam1" / "data" / kFrame).string(), cv::IMREAD_GRAYSCALE);
    if (d.left_raw.empty() || d.right_raw.empty()) throw std::runtime_error(mav0.string() + ": cannot read " + kFrame);
    d.rectifier->rectify(d.left_raw, d.right_raw, d.left, d.right);
    d.left = d.left.clone();
    d.right = d.right.clone();
    d.camera = d.rectifier->camera();
    // KITTI-sized pair: scale so the width is 1241, keep the middle 376 rows.
    const double scale = static_cast<double>(kKittiWidthPx) / d.left.cols;
    cv::Mat big_left, big_right;
    cv::resize(d.left, big_left, cv::Size(), scale, scale, cv::INTER_LINEAR);
    cv::resize(d.right, big_right, cv::Size(), scale, scale, cv::INTER_LINEAR);
    const int top = (big_left.rows - kKittiHeightPx) / 2;
    d.kitti_left = big_left(cv::Rect(0, top, kKittiWidthPx, kKittiHeightPx)).clone();
    d.kitti_right = big_right(cv::Rect(0, top, kKittiWidthPx, kKittiHeightPx)).clone();
    d.kitti_camera = d.camera;
    d.kitti_camera.fx_px *= scale;
    d.kitti_camera.fy_px *= scale;
    d.kitti_camera.cx_px *= scale;
    d.kitti_camera.cy_px = d.kitti_camera.cy_px * scale - top;
    d.kitti_camera.width_px = kKittiWidthPx;
    d.kitti_camera.height_px = kKittiHeightPx;
    return d;
  }();
  return d;
}

bool kitti(const benchmark::State& state) { return state.range(0) == 1; }
const cv::Mat& left_image(const benchmark::State& state) { return kitti(state) ? data().kitti_left : data().left; }
const cv::Mat& right_image(const benchmark::State& state) { return kitti(state) ? data().kitti_right : data().right; }
const PinholeStereo& camera(const benchmark::State& state) {
  return kitti(state) ? data().kitti_camera : data().camera;
}
int features(const benchmark::State& state) { return kitti(state) ? kKittiFeatures : OrbOptions().features; }

OrbOptions orb_options(const benchmark::State& state) {
  OrbOptions o;
  o.features = features(state);
  return o;
}

// Equalized pair as the pipeline would extract from (default HE: global).
std::pair<cv::Mat, cv::Mat> equalized(const benchmark::State& state) {
  cv::Mat l, r;
  HistogramEqualizer().equalize(left_image(state), right_image(state), l, r);
  return {l.clone(), r.clone()};
}

void BM_Rectify(benchmark::State& state) {
  cv::Mat l, r;
  for (auto _ : state) data().rectifier->rectify(data().left_raw, data().right_raw, l, r);
}
BENCHMARK(BM_Rectify)->Unit(benchmark::kMillisecond);

void BM_HistogramEqualizationPair(benchmark::State& state) {
  HistogramEqualizerOptions o;
  o.mode = static_cast<HeMode>(state.range(1));
  HistogramEqualizer equalizer(o);
  cv::Mat l, r;
  for (auto _ : state) equalizer.equalize(left_image(state), right_image(state), l, r);
  state.SetLabel(std::string(to_string(o.mode)) + (kitti(state) ? " kitti" : " euroc"));
}
BENCHMARK(BM_HistogramEqualizationPair)->ArgsProduct({{0, 1}, {0, 1, 2, 3}})->Unit(benchmark::kMillisecond);

// Clipped HE (the default) with the two images' mappings shared or matched (HE.stereo), on the EuRoC
// pair (arg 0 = 0: EuRoC) as recorded (arg 2 = 0) and exposed apart: left x0.35, right x2 clipped
// (arg 2 = 1); arg 1: 0 shared, 1 matched.
void BM_HistogramEqualizationStereo(benchmark::State& state) {
  HistogramEqualizerOptions o;
  o.mode = HeMode::kClipped;
  o.stereo = state.range(1) == 0 ? StereoPhotometry::kShared : StereoPhotometry::kMatched;
  HistogramEqualizer equalizer(o);
  cv::Mat left = left_image(state).clone();
  cv::Mat right = right_image(state).clone();
  if (state.range(2) == 1) {
    left.convertTo(left, CV_8U, 0.35);
    right.convertTo(right, CV_8U, 2.0);
  }
  cv::Mat l, r;
  for (auto _ : state) equalizer.equalize(left, right, l, r);
  state.SetLabel(std::string(to_string(o.stereo)) + (state.range(2) == 1 ? " gains 0.35/2" : " as recorded"));
}
BENCHMARK(BM_HistogramEqualizationStereo)->ArgsProduct({{0}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);

// What matched adds to shared: the tone curves from the two histograms (no pass over the pixels).
void BM_AlignStereoTones(benchmark::State& state) {
  GreyHistogram left{};
  GreyHistogram right{};
  cv::Mat l = left_image(state);
  cv::Mat r;
  right_image(state).convertTo(r, CV_8U, 2.0);
  for (int y = 0; y < l.rows; ++y) {
    for (int x = 0; x < l.cols; ++x) {
      ++left[l.at<std::uint8_t>(y, x)];
      ++right[r.at<std::uint8_t>(y, x)];
    }
  }
  for (auto _ : state) benchmark::DoNotOptimize(align_stereo_tones(left, right, 0.1));
}
BENCHMARK(BM_AlignStereoTones)->Arg(0)->Unit(benchmark::kMicrosecond);

// What tone_from_matches (formerly HE.toneFromMatches) adds per pair exposed apart: the gain and offset from the pair's
// stereo matches (feature/stereo_tone.hpp), here the EuRoC pair at left x0.35 / right x2.
void BM_MeasureStereoTone(benchmark::State& state) {
  const Data& d = data();
  cv::Mat left, right;
  d.left.convertTo(left, CV_8U, 0.35);
  d.right.convertTo(right, CV_8U, 2.0);
  StereoFeaturePipelineOptions options;
  options.parallel = false;
  StereoFeaturePipeline pipeline(d.camera, options);
  const StereoFeatures features = pipeline.process(left, right);
  StereoToneMeasurement measurement;
  for (auto _ : state) benchmark::DoNotOptimize(measurement = measure_stereo_tone(left, right, features));
  state.counters["matches"] = measurement.matches;
}
BENCHMARK(BM_MeasureStereoTone)->Unit(benchmark::kMicrosecond);

void BM_OrbPyramid(benchmark::State& state) {
  OrbExtractor extractor(orb_options(state));
  const cv::Mat image = equalized(state).first;
  for (auto _ : state) extractor.build_pyramid(image);
}
BENCHMARK(BM_OrbPyramid)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// FAST per cell with fallback, quadtree distribution and intensity-centroid orientation.
void BM_OrbDetect(benchmark::State& state) {
  OrbExtractor extractor(orb_options(state));
  extractor.build_pyramid(equalized(state).first);
  for (auto _ : state) extractor.detect();
}
BENCHMARK(BM_OrbDetect)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Gaussian blur of the levels and rBRIEF descriptors.
void BM_OrbDescribe(benchmark::State& state) {
  OrbExtractor extractor(orb_options(state));
  extractor.build_pyramid(equalized(state).first);
  extractor.detect();
  OrbFeatures out;
  for (auto _ : state) extractor.describe(out);
  state.counters["keypoints"] = static_cast<double>(out.keypoints.size());
}
BENCHMARK(BM_OrbDescribe)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_OrbExtractOneImage(benchmark::State& state) {
  OrbExtractor extractor(orb_options(state));
  const cv::Mat image = equalized(state).first;
  OrbFeatures out;
  for (auto _ : state) extractor.extract(image, out);
  state.counters["keypoints"] = static_cast<double>(out.keypoints.size());
}
BENCHMARK(BM_OrbExtractOneImage)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_CvOrbOneImage(benchmark::State& state) {
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(features(state), 1.2f, 8, 19, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  const cv::Mat image = equalized(state).first;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  for (auto _ : state) orb->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
  state.counters["keypoints"] = static_cast<double>(keypoints.size());
}
BENCHMARK(BM_CvOrbOneImage)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_StereoMatch(benchmark::State& state) {
  const auto [l, r] = equalized(state);
  StereoFeaturePipelineOptions defaults;
  OrbOptions right_options = orb_options(state);
  right_options.features = static_cast<int>(right_options.features * defaults.right_features_factor);
  OrbExtractor left_extractor(orb_options(state));
  OrbExtractor right_extractor(right_options);
  OrbFeatures left, right;
  left_extractor.extract(l, left);
  right_extractor.extract(r, right);
  const StereoMatcher matcher(camera(state), left_extractor.scale_pyramid(), defaults.stereo);
  std::vector<float> u_right, depth;
  StereoMatchStats stats;
  for (auto _ : state) matcher.match(left, right, u_right, depth);
  matcher.match(left, right, u_right, depth, &stats);
  state.counters["stereo"] = stats.matched;
}
BENCHMARK(BM_StereoMatch)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// HE + extraction of both images + stereo matching: range(1) 0 = one thread, 1 = left || right.
void BM_Pipeline(benchmark::State& state) {
  StereoFeaturePipelineOptions o;
  o.orb = orb_options(state);
  o.parallel = state.range(1) == 1;
  StereoFeaturePipeline pipeline(camera(state), o);
  StereoFeatureTimings t;
  double he = 0, extract = 0, stereo = 0;
  std::size_t matched = 0;
  for (auto _ : state) {
    const StereoFeatures f = pipeline.process(left_image(state), right_image(state), &t);
    he += t.he_ms;
    extract += t.extract_ms;
    stereo += t.stereo_ms;
    matched = 0;
    for (std::size_t i = 0; i < f.size(); ++i) matched += f.has_stereo(i) ? 1 : 0;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["he_ms"] = he / n;
  state.counters["extract_ms"] = extract / n;
  state.counters["stereo_ms"] = stereo / n;
  state.counters["stereo"] = static_cast<double>(matched);
  state.SetLabel(std::string(kitti(state) ? "kitti" : "euroc") + (o.parallel ? " parallel" : " serial"));
}
BENCHMARK(BM_Pipeline)->ArgsProduct({{0, 1}, {0, 1}})->UseRealTime()->Unit(benchmark::kMillisecond);

// What Pipeline.leftOnlyFeatures adds to a pair whose right camera saturates: the EuRoC pair at left
// x1 / right x4, both threads, without (arg 0) and with (arg 1) the left-only keypoints.
void BM_PipelineRightSaturated(benchmark::State& state) {
  const Data& d = data();
  cv::Mat right;
  d.right.convertTo(right, CV_8U, 4.0);
  StereoFeaturePipelineOptions o;
  o.left_only_features = state.range(0) == 1 ? 1.f : 0.f;
  StereoFeaturePipeline pipeline(d.camera, o);
  std::size_t keypoints = 0;
  std::size_t matched = 0;
  for (auto _ : state) {
    const StereoFeatures f = pipeline.process(d.left, right);
    keypoints = f.size();
    matched = 0;
    for (std::size_t i = 0; i < f.size(); ++i) matched += f.has_stereo(i) ? 1 : 0;
  }
  state.counters["keypoints"] = static_cast<double>(keypoints);
  state.counters["stereo"] = static_cast<double>(matched);
  state.SetLabel(state.range(0) == 1 ? "left-only keypoints" : "none");
}
BENCHMARK(BM_PipelineRightSaturated)->Arg(0)->Arg(1)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace heslam

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  // OpenCV's own thread pool (resize, blur, remap) competes with the pipeline's two threads on a
  // 2-core machine; HESLAM_BENCH_CV_THREADS=1 measures without it.
  if (const char* threads = std::getenv("HESLAM_BENCH_CV_THREADS")) cv::setNumThreads(std::atoi(threads));
  try {
    heslam::data();
  } catch (const std::exception& e) {
    std::cerr << "heslam-bench-vision: " << e.what() << "\n";
    return 1;
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

// Per-frame feature pipeline: HE, ORB left || right, stereo matching split in two halves, and on
// pairs exposed apart the left-only keypoints where the right saturates.
#include "components/core/feature/stereo_feature_pipeline.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <optional>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "components/core/image/yaml_option.hpp"

namespace heslam {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// CPU time of the whole process (all its threads), in ms.
double process_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

// The left image equalized on its own histogram (the joint-histogram steps do not apply to one image).
HistogramEqualizerOptions left_alone_options(const HistogramEqualizerOptions& he) {
  HistogramEqualizerOptions alone = he;
  alone.stereo = StereoPhotometry::kShared;
  return alone;
}

// The left-only region keeps this far (level-0 pixels) from the clip contour, whose corners the
// stereo keypoints already hold: FAST's circle (3) and a little more. MH01 x1/x4, 16 full-system runs
// each: 0 / 1 / 2 / 5 / 10 px gave 4.34 / 4.36 / 4.28 / 4.34 / 4.49 mm, alike up to 5; on the
// synthetic room 2 px was worse than 5 (docs/benchmarks.md at 5c1f792, tenth pass).
constexpr int kLeftOnlyContourMarginPx = 5;

OrbOptions right_options(const StereoFeaturePipelineOptions& options) {
  OrbOptions right = options.orb;
  right.features = static_cast<int>(std::lround(options.orb.features * options.right_features_factor));
  return right;
}

}  // namespace

StereoFeaturePipelineOptions StereoFeaturePipelineOptions::from_yaml(const cv::FileNode& root,
                                                                     const std::string& source) {
  StereoFeaturePipelineOptions o;
  o.he = HistogramEqualizerOptions::from_yaml(root, source);
  o.orb = OrbOptions::from_yaml(root, source);
  o.stereo = StereoMatcherOptions::from_yaml(root, source);
  yaml_option::read(root, "Pipeline.parallel", source, o.parallel);
  yaml_option::read(root, "Pipeline.pinThreads", source, o.pin_threads);
  yaml_option::read(root, "Pipeline.leftOnlyFeatures", source, o.left_only_features);
  if (!(o.left_only_features >= 0.f) || o.left_only_features > 4.f) {
    yaml_option::fail(source, "Pipeline.leftOnlyFeatures", "a number in [0, 4]");
  }
  return o;
}

StereoFeaturePipelineOptions StereoFeaturePipelineOptions::load(const std::filesystem::path& settings_yaml) {
  cv::FileStorage fs;
  try {
    fs.open(settings_yaml.string(), cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(settings_yaml.string() + ": not valid YAML (" + e.err + ")");
  }
  if (!fs.isOpened()) throw std::runtime_error(settings_yaml.string() + ": cannot open file");
  return from_yaml(fs.root(), settings_yaml.string());
}

StereoFeaturePipeline::StereoFeaturePipeline(const PinholeStereo& camera, const StereoFeaturePipelineOptions& options)
    : camera_(camera),
      options_(options),
      equalizer_(options.he),
      left_extractor_(options.orb),
      right_extractor_(right_options(options)),
      stereo_matcher_(camera, left_extractor_.scale_pyramid(), options.stereo),
      left_alone_equalizer_(left_alone_options(options.he)),
      left_only_extractor_(options.orb) {
  if (camera.width_px <= 0 || camera.height_px <= 0 || !(camera.fx_px > 0.0) || !(camera.baseline_m > 0.0)) {
    throw std::invalid_argument("StereoFeaturePipeline: expected a rectified camera with size, fx and baseline");
  }
  if (options.parallel) {
    PairWorkerOptions worker_options;
    worker_options.pin_to_two_cpus = options.pin_threads;
    worker_ = std::make_unique<PairWorker>(worker_options);
  }
}

void StereoFeaturePipeline::run_on_both(const std::function<void()>& right_job, const std::function<void()>& left_job) {
  if (worker_) {
    worker_->run(right_job, left_job);
  } else {
    left_job();
    right_job();
  }
}

void StereoFeaturePipeline::check_image(const cv::Mat& image, const char* side) const {
  const cv::Size expected(camera_.width_px, camera_.height_px);
  if (image.type() != CV_8UC1 || image.size() != expected) {
    throw std::invalid_argument(std::string("StereoFeaturePipeline: expected an 8-bit grey ") + side + " image of " +
                                std::to_string(expected.width) + "x" + std::to_string(expected.height) + ", got " +
                                std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                                (image.type() == CV_8UC1 ? "" : " not 8-bit grey"));
  }
}

StereoFeatures StereoFeaturePipeline::process(const cv::Mat& left_rect, const cv::Mat& right_rect,
                                              StereoFeatureTimings* timings) {
  check_image(left_rect, "left");
  check_image(right_rect, "right");
  StereoFeatures out = process_from([&]() -> const cv::Mat& { return left_rect; },
                                    [&]() -> const cv::Mat& { return right_rect; }, timings);
  if (timings) {  // nothing to make: the "source" step was the histograms, part of HE here
    timings->he_ms += timings->source_ms;
    timings->total_ms += timings->source_ms;
  }
  return out;
}

StereoFeatures StereoFeaturePipeline::process_raw(const StereoRectifier& rectifier, const cv::Mat& left_raw,
                                                  const cv::Mat& right_raw, cv::Mat& left_rect, cv::Mat& right_rect,
                                                  StereoFeatureTimings* timings) {
  return process_from(
      [&]() -> const cv::Mat& {
        rectifier.rectify_left(left_raw, left_rect);
        return left_rect;
      },
      [&]() -> const cv::Mat& {
        rectifier.rectify_right(right_raw, right_rect);
        return right_rect;
      },
      timings);
}

StereoFeatures StereoFeaturePipeline::process_from(const ImageSource& left_source, const ImageSource& right_source,
                                                   StereoFeatureTimings* timings) {
  using Side = HistogramEqualizer::Side;
  const Clock::time_point t0 = Clock::now();
  const double cpu0_ms = timings ? process_cpu_ms() : 0.0;
  const cv::Mat* left_image = nullptr;
  const cv::Mat* right_image = nullptr;
  // Each thread: its image, then its histogram (the image still in its core's cache).
  auto make_left = [&] {
    left_image = &left_source();
    check_image(*left_image, "left");
    equalizer_.add_histogram(Side::kLeft, *left_image);
  };
  auto make_right = [&] {
    right_image = &right_source();
    check_image(*right_image, "right");
    equalizer_.add_histogram(Side::kRight, *right_image);
  };
  // Each thread maps its image and builds its pyramid.
  auto start_left = [&] {
    left_he_ = equalizer_.apply(Side::kLeft, *left_image, left_he_buffer_);
    if (worker_) left_extractor_.build_pyramid(left_he_);
  };
  auto start_right = [&] {
    right_he_ = equalizer_.apply(Side::kRight, *right_image, right_he_buffer_);
    if (worker_) right_extractor_.build_pyramid(right_he_);
  };

  // The mappings follow at once, then the pyramids: the worker polls in between.
  if (worker_) {
    worker_->run(make_right, make_left, PairWorker::Then::kMoreSoon);
  } else {
    make_left();
    make_right();
  }
  const Clock::time_point t1 = Clock::now();
  const double cpu1_ms = timings ? process_cpu_ms() : 0.0;
  equalizer_.compute_mappings();
  // Whether the tone is followed decides on the histograms' own curve, so that the curve applied
  // cannot switch it off and on from pair to pair.
  const bool follow_tone =
      options_.tone_from_matches && options_.he.stereo == StereoPhotometry::kMatched && equalizer_.last_exposed_apart();
  if (follow_tone) {
    if (const std::optional<LinearTone> tone = tone_tracker_.predict(equalizer_.last_histogram_tone())) {
      equalizer_.compute_mappings(&*tone);
    }
  }
  const Clock::time_point t1b = Clock::now();

  if (worker_) {
    // Pyramids: one per thread. Then the (image, level) jobs, largest first, taken by whichever
    // thread is free: the right image has more features, so a fixed left || right split would leave
    // one core idle. Each job writes only its own level, so the result does not depend on which
    // thread ran it.
    // The level jobs follow at once, and stereo matching after them: the worker polls in between.
    worker_->run(start_right, start_left, PairWorker::Then::kMoreSoon);
    const int levels = options_.orb.levels;
    std::atomic<int> next_job{0};
    auto run_jobs = [&] {
      for (int job = next_job++; job < 2 * levels; job = next_job++) {
        OrbExtractor& extractor = job % 2 == 0 ? right_extractor_ : left_extractor_;
        extractor.detect_and_describe_level(job / 2);
      }
    };
    worker_->run(run_jobs, run_jobs, PairWorker::Then::kMoreSoon);
    left_extractor_.collect(left_);
    right_extractor_.collect(right_);
  } else {
    start_left();
    start_right();
    left_extractor_.extract(left_he_, left_);
    right_extractor_.extract(right_he_, right_);
  }
  const Clock::time_point t2 = Clock::now();

  StereoFeatures out;
  out.pyramid = left_extractor_.scale_pyramid();
  const std::size_t n = left_.keypoints.size();
  out.u_right_px.assign(n, kNoStereo);
  out.depth_m.assign(n, kNoStereo);
  // Cameras exposed apart: the matched HE applied a tone curve (see the header's clip_edge).
  const bool exposed_apart = options_.he.stereo == StereoPhotometry::kMatched && equalizer_.last_exposed_apart();
  stereo_matcher_.prepare_rows(right_, right_rows_);
  sad_left_half_.clear();
  sad_right_half_.clear();
  const std::size_t half = n / 2;
  auto first_half = [&] {
    stereo_matcher_.match_range(left_, right_, right_rows_, 0, half, out.u_right_px, out.depth_m, sad_left_half_);
  };
  auto second_half = [&] {
    stereo_matcher_.match_range(left_, right_, right_rows_, half, n, out.u_right_px, out.depth_m, sad_right_half_);
  };
  // Left-only keypoints (pairs exposed apart) need only the left image and its equalization: on a
  // pair that has them the second thread makes them while the caller does the whole stereo matching
  // (the same output as one after the other; the time measured in docs/benchmarks.md at 5c1f792, tenth pass).
  const bool left_only = exposed_apart && options_.left_only_features > 0.f;
  if (left_only) prepare_left_only_region(*left_image);
  const bool left_only_wanted = left_only && left_only_wanted_ > 0;
  auto left_only_job = [&] { extract_left_only(*left_image); };
  if (worker_ && left_only_wanted) {
    auto all_stereo = [&] {
      first_half();
      second_half();
    };
    worker_->run(left_only_job, all_stereo, PairWorker::Then::kSleep);  // the frame's last hand-off
  } else if (worker_) {
    worker_->run(second_half, first_half, PairWorker::Then::kSleep);  // the frame's last hand-off
  } else {
    first_half();
    second_half();
    if (left_only_wanted) left_only_job();
  }
  sad_left_half_.insert(sad_left_half_.end(), sad_right_half_.begin(), sad_right_half_.end());
  stereo_matcher_.reject_outliers(sad_left_half_, out.u_right_px, out.depth_m);
  out.keypoints = left_.keypoints;
  out.descriptors = left_.descriptors;
  if (exposed_apart && options_.clip_edge.radius_px > 0) {
    mark_near_clip(clipped_pixel_mask(left_he_, options_.clip_edge.min_clipped_fraction),
                   clipped_pixel_mask(right_he_, options_.clip_edge.min_clipped_fraction), options_.clip_edge, out);
  }
  if (left_only_wanted) append_left_only(out);
  if (follow_tone) {
    tone_tracker_.update(measure_stereo_tone(*left_image, *right_image, out), equalizer_.last_histogram_tone());
  } else {
    tone_tracker_.reset();
  }
  const Clock::time_point t3 = Clock::now();

  if (timings) {
    timings->source_ms = ms_between(t0, t1);
    timings->source_cpu_ms = cpu1_ms - cpu0_ms;
    timings->he_ms = ms_between(t1, t1b);
    timings->extract_ms = ms_between(t1b, t2);
    timings->stereo_ms = ms_between(t2, t3);
    timings->total_ms = ms_between(t1, t3);
  }
  return out;
}

void StereoFeaturePipeline::prepare_left_only_region(const cv::Mat& left_raw) {
  left_only_wanted_ = 0;
  // Where the equalized left sits on its top plateau but the raw left does not saturate: the left
  // was clipped there to the right's range.
  const int top = clipped_top_level(left_he_, options_.clip_edge.min_clipped_fraction);
  if (top > 255) return;
  const cv::Mat region = (left_he_ >= top) & (left_raw < 255);
  const int side = 2 * kLeftOnlyContourMarginPx + 1;
  cv::erode(region, left_only_region_, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(side, side)));
  const double share =
      static_cast<double>(cv::countNonZero(left_only_region_)) / static_cast<double>(left_only_region_.total());
  left_only_wanted_ = static_cast<int>(std::lround(options_.left_only_features * options_.orb.features * share));
}

void StereoFeaturePipeline::extract_left_only(const cv::Mat& left_raw) {
  using Side = HistogramEqualizer::Side;
  left_alone_equalizer_.add_histogram(Side::kLeft, left_raw);
  left_alone_equalizer_.add_histogram(Side::kRight, left_raw);
  left_alone_equalizer_.compute_mappings();
  const cv::Mat& left_alone = left_alone_equalizer_.apply(Side::kLeft, left_raw, left_alone_buffer_);
  left_only_extractor_.set_region(left_only_region_, left_only_wanted_);
  left_only_extractor_.extract(left_alone, left_only_);
}

void StereoFeaturePipeline::append_left_only(StereoFeatures& out) const {
  out.keypoints.insert(out.keypoints.end(), left_only_.keypoints.begin(), left_only_.keypoints.end());
  out.descriptors.insert(out.descriptors.end(), left_only_.descriptors.begin(), left_only_.descriptors.end());
  out.u_right_px.resize(out.keypoints.size(), kNoStereo);
  out.depth_m.resize(out.keypoints.size(), kNoStereo);
  if (!out.near_clip.empty()) out.near_clip.resize(out.keypoints.size(), 0);
}

}  // namespace heslam

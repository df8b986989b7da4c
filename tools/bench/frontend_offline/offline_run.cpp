// The offline frontend loop and its trajectory evaluation.
#include "tools/bench/frontend_offline/offline_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <stdexcept>
#include <thread>

#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "tools/eval/alignment.hpp"

namespace heslam::bench {
namespace {

double thread_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

double process_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

cv::Mat read_grey(const std::filesystem::path& png) {
  cv::Mat image = cv::imread(png.string(), cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw std::runtime_error(png.string() + ": cannot read image (expected an 8-bit PNG)");
  return image;
}

}  // namespace

int OfflineRun::tracked_frames() const {
  int n = 0;
  for (const FrameRecord& f : frames) n += f.state == TrackingState::kOk ? 1 : 0;
  return n;
}

OfflineRun run_offline(const EurocSequence& sequence, const OfflineRunOptions& options) {
  StereoCalibration calibration = load_euroc_calibration(sequence.mav0_dir);
  if (options.k1_offset != 0.0) apply_k1_offset(calibration, options.k1_offset);
  const StereoRectifier rectifier(calibration);
  OfflineRun run;
  run.camera = rectifier.camera();
  StereoFeaturePipeline pipeline(run.camera, options.pipeline);
  Tracker tracker(run.camera, options.tracker, options.vocabulary);

  const std::size_t first =
      std::min(sequence.frames.size(), static_cast<std::size_t>(std::max(options.first_frame, 0)));
  const std::size_t available = sequence.frames.size() - first;
  const std::size_t count =
      options.max_frames > 0 ? std::min(available, static_cast<std::size_t>(options.max_frames)) : available;
  cv::Mat left_rect;
  cv::Mat right_rect;
  // k is the frame's index in the sequence, so a run that skips frames sees the same noise per frame.
  auto next_frame_start = std::chrono::steady_clock::now();
  for (std::size_t k = first; k < first + count; ++k) {
    if (options.period_ms > 0.0) {
      std::this_thread::sleep_until(next_frame_start);
      next_frame_start =
          std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                 std::chrono::duration<double, std::milli>(options.period_ms));
    }
    const EurocFrame& input = sequence.frames[k];
    cv::Mat left = read_grey(input.left_png);
    cv::Mat right = read_grey(input.right_png);
    photometric::apply_to_pair(left, right, options.variant,
                               photometric::stereo_gain_at(options.stereo_gain, k - first, count),
                               static_cast<std::uint64_t>(k));

    FrameRecord record;
    record.stamp_ns = input.stamp_ns;
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = process_cpu_ms();
    // As the frontend's FrameProcessor: each image rectified on its own thread of the pipeline's pair,
    // which goes on with it (histogram, HE mapping, pyramid).
    StereoFeatureTimings timings;
    StereoFeatures features = pipeline.process_raw(rectifier, left, right, left_rect, right_rect, &timings);
    if (options.disparity_noise_px > 0.0) {
      add_disparity_noise(features, rectifier.camera(), options.disparity_noise_px, static_cast<std::uint64_t>(k));
    }
    if (options.drop_stereo_right_above >= 0)
      drop_stereo_right_above(features, right_rect, options.drop_stereo_right_above);
    record.rectify_ms = timings.source_ms;
    record.rectify_cpu_ms = timings.source_cpu_ms;
    record.he_ms = timings.he_ms;
    record.extract_ms = timings.extract_ms;
    record.stereo_ms = timings.stereo_ms;
    record.features = static_cast<int>(features.size());
    for (std::size_t i = 0; i < features.size(); ++i) {
      record.stereo_features += features.has_stereo(i) ? 1 : 0;
      record.near_clip_features += features.stereo_near_clip(i) ? 1 : 0;
    }
    const auto track_start = std::chrono::steady_clock::now();
    const double track_cpu_start = thread_cpu_ms();
    const double track_process_cpu_start = process_cpu_ms();
    const TrackResult result = tracker.track(input.stamp_ns, k, std::move(features));
    record.tracking_cpu_ms = thread_cpu_ms() - track_cpu_start;
    record.tracking_process_cpu_ms = process_cpu_ms() - track_process_cpu_start;
    record.tracking_ms = elapsed_ms(track_start);
    record.total_ms = elapsed_ms(start);
    record.cpu_ms = process_cpu_ms() - cpu_start;
    record.state = result.state;
    record.method = result.method;
    record.T_wc = result.T_wc;
    record.map_id = result.map_id;
    record.tracked_points = result.tracked_points;
    record.keyframe = result.new_keyframe.has_value();
    record.motion = result.motion;
    if (input.T_WB_truth) record.T_wc_truth = *input.T_WB_truth * rectifier.T_B_rect();
    run.frames.push_back(record);
  }
  run.keyframes = static_cast<int>(tracker.local_map().keyframes.size());
  for (const auto& [id, point] : tracker.local_map().points) {
    for (const auto& [keyframe_id, index] : point.observations) {
      const Keyframe* keyframe = tracker.local_map().keyframe(keyframe_id);
      if (keyframe != nullptr && keyframe->map_id != point.map_id) ++run.cross_map_observations;
    }
  }
  for (const auto& [id, keyframe] : tracker.local_map().keyframes) ++run.keyframes_per_map[keyframe.map_id];
  run.map_points = static_cast<int>(tracker.local_map().points.size());
  run.hand_offs = pipeline.hand_offs();
  run.sleeping_hand_offs = pipeline.sleeping_hand_offs();
  run.threads_pinned = pipeline.threads_pinned();
  return run;
}

int add_disparity_noise(StereoFeatures& features, const PinholeStereo& camera, double sigma_px, std::uint64_t seed) {
  cv::RNG rng(seed);
  int lost = 0;
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!features.has_stereo(i)) continue;
    const float u_px = features.keypoints[i].u_px;
    const auto disparity_px = static_cast<float>(u_px - features.u_right_px[i] + rng.gaussian(sigma_px));
    if (disparity_px <= kMinNoisyDisparityPx) {
      features.u_right_px[i] = kNoStereo;
      features.depth_m[i] = kNoStereo;
      ++lost;
      continue;
    }
    features.u_right_px[i] = u_px - disparity_px;
    features.depth_m[i] = static_cast<float>(camera.bf() / disparity_px);
  }
  return lost;
}

void apply_k1_offset(StereoCalibration& calibration, double offset) {
  for (CameraModel* camera : {&calibration.left, &calibration.right}) {
    if (calibration.input_rectified || camera->distortion.empty()) {
      throw std::invalid_argument(calibration.source + ": " + (camera == &calibration.left ? "left" : "right") +
                                  " camera has no radial distortion coefficient to offset");
    }
    camera->distortion[0] += offset;
  }
}

int drop_stereo_right_above(StereoFeatures& features, const cv::Mat& right_rect, int level) {
  if (right_rect.type() != CV_8UC1 || right_rect.empty()) {
    throw std::invalid_argument("drop_stereo_right_above: the right image must be 8-bit grey and non-empty");
  }
  int dropped = 0;
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!features.has_stereo(i)) continue;
    const int x = std::clamp(static_cast<int>(std::lround(features.u_right_px[i])), 0, right_rect.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(features.keypoints[i].v_px)), 0, right_rect.rows - 1);
    if (right_rect.at<std::uint8_t>(y, x) <= level) continue;
    features.u_right_px[i] = kNoStereo;
    features.depth_m[i] = kNoStereo;
    ++dropped;
  }
  return dropped;
}

std::optional<AteResult> compute_ate_se3(const OfflineRun& run) {
  std::vector<Eigen::Vector3d> estimate;
  std::vector<Eigen::Vector3d> truth;
  for (const FrameRecord& f : run.frames) {
    if (f.state != TrackingState::kOk || !f.T_wc_truth) continue;
    estimate.push_back(f.T_wc.translation());
    truth.push_back(f.T_wc_truth->translation());
  }
  if (estimate.size() < 3) return std::nullopt;
  const eval::Sim3 S = eval::umeyama(estimate, truth, /*with_scale=*/false);
  AteResult ate;
  double sum2 = 0.0;
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    const double e = (S.R * estimate[i] + S.t - truth[i]).norm();
    sum2 += e * e;
    ate.max_m = std::max(ate.max_m, e);
  }
  ate.pairs = static_cast<int>(estimate.size());
  ate.rmse_m = std::sqrt(sum2 / static_cast<double>(estimate.size()));
  return ate;
}

std::optional<eval::KittiResult> compute_kitti_drift(const OfflineRun& run) {
  eval::Trajectory truth;
  eval::Trajectory estimate;
  for (std::size_t k = 0; k < run.frames.size(); ++k) {
    const FrameRecord& f = run.frames[k];
    if (f.state != TrackingState::kOk || !f.T_wc_truth) continue;
    truth.push_back(*f.T_wc_truth, static_cast<std::int64_t>(k));
    estimate.push_back(f.T_wc, static_cast<std::int64_t>(k));
  }
  const eval::KittiOptions options;
  if (truth.size() < 2 || truth.path_length_m() < options.lengths_m.front()) return std::nullopt;
  return eval::compute_kitti_metrics(truth, estimate, options);
}

double tracked_path_length_m(const OfflineRun& run) {
  double length = 0.0;
  const FrameRecord* previous = nullptr;
  for (const FrameRecord& f : run.frames) {
    if (f.state != TrackingState::kOk) continue;
    if (previous != nullptr) length += (f.T_wc.translation() - previous->T_wc.translation()).norm();
    previous = &f;
  }
  return length;
}

void write_tum_trajectory(const std::filesystem::path& path, const OfflineRun& run) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot write the trajectory");
  out << "# timestamp[s] tx ty tz qx qy qz qw (rectified left camera, tracked frames only)\n";
  out << std::setprecision(9) << std::fixed;
  for (const FrameRecord& f : run.frames) {
    if (f.state != TrackingState::kOk) continue;
    const Eigen::Quaterniond q(f.T_wc.rotation());
    const Eigen::Vector3d t = f.T_wc.translation();
    // Seconds printed from the integer nanoseconds: a double would round the last digits.
    out << f.stamp_ns / 1'000'000'000 << '.' << std::setw(9) << std::setfill('0') << f.stamp_ns % 1'000'000'000
        << std::setfill(' ') << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' '
        << q.z() << ' ' << q.w() << '\n';
  }
}

}  // namespace heslam::bench

// The per-frame chain: rectify, extract stereo features, track; each stage timed.
#include "components/frontend/frame_processor.hpp"

#include <chrono>
#include <ctime>
#include <stdexcept>
#include <utility>

namespace heslam::frontend {
namespace {

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// CPU time of the whole process (all its threads), in ms: over a frame, the work done for it on
// both cores (plus DDS's threads meanwhile), against which "total" shows the waiting.
double process_cpu_ms() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

}  // namespace

FrameProcessor::FrameProcessor(const StereoCalibration& calibration, const FrontendOptions& options)
    : rectifier_(calibration),
      pipeline_(rectifier_.camera(), options.features),
      tracker_(rectifier_.camera(), options.tracker, options.vocabulary) {}

FrameOutput FrameProcessor::process(std::int64_t stamp_ns, std::uint64_t seq, const cv::Mat& left_raw,
                                    const cv::Mat& right_raw) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start_ms = process_cpu_ms();
  const cv::Size raw = rectifier_.raw_size();
  for (const auto& [image, side] : {std::pair{&left_raw, "left"}, std::pair{&right_raw, "right"}}) {
    if (image->size() != raw) {
      throw std::runtime_error("stereo frame " + std::to_string(seq) + ": " + side + " image is " +
                               std::to_string(image->cols) + "x" + std::to_string(image->rows) +
                               ", the calibration expects " + std::to_string(raw.width) + "x" +
                               std::to_string(raw.height));
    }
  }
  // Each image rectified on its own thread of the feature pipeline's pair, which goes on with it
  // (histogram, HE mapping, pyramid) on the same thread: one hand-off for rectification and HE, no
  // OpenCV pool (cv::remap's parallel_for serializes a second concurrent call and needs its pool's
  // worker awake, which a real-time frontend idle between frames often has to wake first).
  StereoFeatureTimings feature_timings;
  StereoFeatures features =
      pipeline_.process_raw(rectifier_, left_raw, right_raw, left_rect_, right_rect_, &feature_timings);
  const double rectify_ms = feature_timings.source_ms;
  FrameOutput output;
  output.keypoints = static_cast<std::uint32_t>(features.size());
  for (std::size_t i = 0; i < features.size(); ++i) output.stereo_keypoints += features.has_stereo(i) ? 1 : 0;

  output.result = tracker_.track(stamp_ns, seq, std::move(features));
  const TrackTimings& track = output.result.timings;
  output.timings = {
      {"rectify", rectify_ms},
      {"he", feature_timings.he_ms},
      {"extract", feature_timings.extract_ms},
      {"stereo", feature_timings.stereo_ms},
      {"features", feature_timings.total_ms},
      {"track_initial", track.initial_pose_ms},
      {"track_local_map", track.local_map_ms},
      {"track_keyframe", track.keyframe_ms},
      {"track", track.total_ms},
      {"cpu", process_cpu_ms() - cpu_start_ms},
      {"total", ms_since(start)},
  };
  return output;
}

}  // namespace heslam::frontend

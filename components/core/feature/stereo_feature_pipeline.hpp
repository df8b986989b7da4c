// The per-frame feature pipeline: rectified stereo pair -> joint histogram equalization -> ORB on
// both images (pyramid levels of both spread over two threads) -> stereo matching -> StereoFeatures.
// On two threads: each image is made (rectified), measured (histogram), mapped (HE) and turned into
// its pyramid on its own thread; the pair meets only to combine the histograms, to share out the
// pyramid levels' jobs and to split the stereo matching. On a pair exposed apart whose right camera
// saturates where the left still sees, monocular keypoints from there follow (left_only_features).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "components/core/feature/features.hpp"
#include "components/core/feature/orb_extractor.hpp"
#include "components/core/feature/pair_worker.hpp"
#include "components/core/feature/stereo_tone.hpp"
#include "components/core/image/histogram_equalizer.hpp"
#include "components/core/match/clip_edge.hpp"
#include "components/core/match/stereo_matcher.hpp"

namespace heslam {

struct StereoFeaturePipelineOptions {
  HistogramEqualizerOptions he;
  OrbOptions orb;
  StereoMatcherOptions stereo;
  // Stereo matches near a clip edge are marked (StereoFeatures::near_clip) only in pairs whose
  // cameras are exposed apart, i.e. where HE.stereo: matched applies a tone curve (its mean shift at
  // least HE.matchShiftFrom): equally exposed pairs keep their features exactly. A constant (measured
  // once: clip_edge.hpp), not a settings key.
  ClipEdgeOptions clip_edge;
  // HE.stereo matched, cameras exposed apart: the right image's tone curve is the cameras' relation
  // measured on the previous pair's stereo matches (stereo_tone.hpp) instead of the quantile curve
  // between the two histograms; false: the quantile curve, as before. A constant (measured better on
  // every exposure pair, docs/vision.md), not a settings key.
  bool tone_from_matches = true;
  // Two threads: the pyramid levels of both images as jobs, then halves of stereo matching.
  bool parallel = true;
  // The two threads pinned to two different CPUs (PairWorkerOptions::pin_to_two_cpus: the first two
  // the process may use); false leaves their placement to the scheduler.
  bool pin_threads = true;
  // The right image keeps this many times orb.features (its keypoints serve only stereo matching):
  // the quadtree picks partly different corners in the two images, and a left keypoint whose
  // counterpart was not kept on the right cannot get a depth. See docs/vision.md for the measurement.
  // A constant, not a settings key.
  float right_features_factor = 2.0f;
  // Cameras exposed apart, the left clipped to the right's range by the matched HE (the right
  // saturates where the left still sees): the left's own texture there, equalized on the left's
  // histogram alone, gives monocular keypoints (no stereo depth possible), this many times
  // orb.features x the region's share of the image, appended after the stereo keypoints. 0: none
  // (the clipped left only). Equally exposed pairs are not touched. Pipeline.leftOnlyFeatures; see
  // docs/vision.md for the measurement.
  float left_only_features = 1.0f;

  // Reads the HE.*, ORBextractor.* and Stereo.* keys of its parts, Pipeline.parallel,
  // Pipeline.pinThreads and Pipeline.leftOnlyFeatures (docs/frontend.md lists them all).
  static StereoFeaturePipelineOptions from_yaml(const cv::FileNode& root, const std::string& source);
  // Same, from a settings file (e.g. config/camera/EuRoC.yaml). Throws std::runtime_error naming the
  // file and key on bad input.
  static StereoFeaturePipelineOptions load(const std::filesystem::path& settings_yaml);
  bool operator==(const StereoFeaturePipelineOptions&) const = default;
};

struct StereoFeatureTimings {
  // Making both images (process_from: e.g. rectifying them; process: nothing) and their histograms,
  // wall time and the process's CPU time over it (both threads).
  double source_ms = 0.0;
  double source_cpu_ms = 0.0;
  // The equalization's mappings from the two histograms (one thread, between two hand-offs); the
  // histograms are in source_ms (process_from) or here (process), the mappings' application is in
  // extract_ms (each thread maps its image, then builds its pyramid).
  double he_ms = 0.0;
  double extract_ms = 0.0;
  double stereo_ms = 0.0;
  // he + extract + stereo (process: the whole call, the histograms included).
  double total_ms = 0.0;
};

class StereoFeaturePipeline {
 public:
  StereoFeaturePipeline(const PinholeStereo& camera, const StereoFeaturePipelineOptions& options);

  // Inputs: rectified 8-bit grey images of the camera's size. Output: StereoFeatures, fully filled.
  // Deterministic: the same sequence of pairs gives the same outputs whether parallel or not (a pair
  // exposed apart uses the tone measured on the pair before it, see tone_from_matches). Not thread-safe.
  StereoFeatures process(const cv::Mat& left_rect, const cv::Mat& right_rect, StereoFeatureTimings* timings = nullptr);

  // Makes an image of the pair on the calling thread (e.g. rectifies a raw image into a buffer it
  // owns) and returns it; it must stay valid until process_from returns.
  using ImageSource = std::function<const cv::Mat&()>;
  // As process(), the images made by `left_source` (on the caller) and `right_source` (on the
  // pipeline's second thread) at once: each thread measures its image's histogram right after making
  // it, the equalization's mappings follow once, and each thread maps its image and goes on to its
  // pyramid -- the making and the equalization share the frame's first hand-off. The same output as
  // process() on the made images. Exceptions of the sources are rethrown here.
  StereoFeatures process_from(const ImageSource& left_source, const ImageSource& right_source,
                              StereoFeatureTimings* timings = nullptr);

  // process_from() with each raw image rectified by `rectifier` on its own thread of the pair into
  // the caller's buffer (kept for reuse across frames): the frontend's and the offline harness's chain.
  StereoFeatures process_raw(const StereoRectifier& rectifier, const cv::Mat& left_raw, const cv::Mat& right_raw,
                             cv::Mat& left_rect, cv::Mat& right_rect, StereoFeatureTimings* timings = nullptr);

  // Runs `right_job` on the pipeline's second thread and `left_job` on the caller at once (one after
  // the other when not parallel): the same thread pair, no second worker. Exceptions are rethrown
  // here. (The frontend rectifies through process_from, which saves a hand-off.)
  void run_on_both(const std::function<void()>& right_job, const std::function<void()>& left_job);

  // Hand-offs between the pipeline's two threads so far, and how many found the other asleep (a
  // futex wake-up); 0 when not parallel.
  std::uint64_t hand_offs() const { return worker_ ? worker_->runs() : 0; }
  std::uint64_t sleeping_hand_offs() const { return worker_ ? worker_->sleeping_hand_offs() : 0; }
  // The pair's two threads pinned to two CPUs (after the first frame), for benchmarks and logs.
  bool threads_pinned() const { return worker_ && worker_->pinned(); }

  // Whether the last pair was equalized (adaptive HE switches on and off).
  bool he_active() const { return equalizer_.active(); }
  const StereoFeaturePipelineOptions& options() const { return options_; }
  const PinholeStereo& camera() const { return camera_; }

 private:
  PinholeStereo camera_;
  StereoFeaturePipelineOptions options_;
  HistogramEqualizer equalizer_;
  OrbExtractor left_extractor_;
  OrbExtractor right_extractor_;
  StereoMatcher stereo_matcher_;
  StereoToneTracker tone_tracker_;
  // left_only_features: the left's own equalization and the extractor of the region only it sees.
  HistogramEqualizer left_alone_equalizer_;
  OrbExtractor left_only_extractor_;
  cv::Mat left_alone_buffer_, left_only_region_;
  int left_only_wanted_ = 0;  // keypoints wanted in left_only_region_ this pair
  OrbFeatures left_only_;
  // The pair's left-only region and how many keypoints it wants (after the equalization).
  void prepare_left_only_region(const cv::Mat& left_raw);
  // The left equalized alone and its keypoints in the region, into left_only_ (any thread).
  void extract_left_only(const cv::Mat& left_raw);
  // Appends left_only_ (monocular keypoints) to `out`.
  void append_left_only(StereoFeatures& out) const;
  // Checks a made image's type and size; `side` names it in the message.
  void check_image(const cv::Mat& image, const char* side) const;

  std::unique_ptr<PairWorker> worker_;        // only when parallel
  cv::Mat left_he_, right_he_;                // the equalized images: a buffer below or the input itself
  cv::Mat left_he_buffer_, right_he_buffer_;  // written by the equalizer, reused frame to frame
  OrbFeatures left_, right_;
  std::vector<std::vector<int>> right_rows_;
  std::vector<std::pair<int, int>> sad_left_half_, sad_right_half_;
};

}  // namespace heslam

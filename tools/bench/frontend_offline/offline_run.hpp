// Runs the frontend's per-frame work (rectify -> HE -> ORB -> stereo -> track) over an EuRoC sequence
// in one thread, without DDS, and evaluates the left-camera trajectory against the ground truth.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/camera/stereo_calibration.hpp"
#include "components/core/feature/stereo_feature_pipeline.hpp"
#include "components/core/tracking/tracker.hpp"
#include "tools/bench/frontend_offline/euroc_sequence.hpp"
#include "tools/eval/kitti_metrics.hpp"
#include "tools/photometric/photometric_variant.hpp"

namespace heslam::bench {

// The offline run's image transforms are heslam-photometric's (tools/photometric).
using photometric::describe;
using photometric::parse_photometric_variant;
using photometric::parse_stereo_gain_schedule;
using photometric::PhotometricVariant;
using photometric::StereoGain;
using photometric::to_string;

struct OfflineRunOptions {
  StereoFeaturePipelineOptions pipeline;
  TrackerOptions tracker;
  // Null: no keyframe database, a lost frame is relocalized against the newest keyframes only.
  std::shared_ptr<const Vocabulary> vocabulary;
  PhotometricVariant variant = PhotometricVariant::kNone;
  // Per-camera exposure, applied after the variant: empty = equal exposure; several entries split
  // the run into equal consecutive blocks of frames.
  std::vector<StereoGain> stereo_gain;
  int first_frame = 0;  // frames of the sequence skipped: the run starts (initializes) here
  int max_frames = 0;   // 0: the whole sequence
  // > 0: each frame starts this long after the previous one (a camera's period; the decoding of the
  // next pair inside it), the cores idle in between as in a real-time run. 0: back to back.
  double period_ms = 0.0;
  // > 0: Gaussian noise of this sigma (level-0 pixels) added to every stereo disparity, seeded by the
  // frame's index (repeatable). A diagnostic: how much trajectory scale does stereo noise alone cost?
  // (Cameras exposed apart, docs/benchmarks.md at 5c1f792, tenth session.)
  double disparity_noise_px = 0.0;
  // In 0..254: every stereo match whose right pixel (the rectified right image the pipeline matched
  // on, before HE) is brighter than this loses its stereo match. With equal exposure this is the set
  // of stereo points a right camera gained by 255 / level would leave, without changing any pixel: a
  // diagnostic that separates which points get depth from how their images look (docs/benchmarks.md,
  // "Cameras exposed apart, seventh pass"). -1: off.
  int drop_stereo_right_above = -1;
  // Added to the first radial distortion coefficient (k1) of both cameras before rectification: a
  // diagnostic of how much the trajectory depends on the lens model at the image's edges
  // (docs/benchmarks.md at 5c1f792, Cameras exposed apart seventh pass). 0: the calibration as read.
  double k1_offset = 0.0;
};

struct FrameRecord {
  std::int64_t stamp_ns = 0;
  TrackingState state = TrackingState::kNotInitialized;
  TrackingMethod method = TrackingMethod::kNone;
  Pose3 T_wc = Pose3::Identity();   // rectified left camera in the tracker's world
  MapId map_id = kFirstMapId;       // ... of this map (the atlas: TrackerOptions::new_map_after_ns)
  std::optional<Pose3> T_wc_truth;  // rectified left camera in the ground-truth world
  int features = 0;
  int stereo_features = 0;
  int near_clip_features = 0;  // stereo features marked near a clip edge (StereoFeatures::near_clip)
  int tracked_points = 0;
  bool keyframe = false;
  FrameMotion motion = FrameMotion::kMoving;  // the tracker's stationary test
  double rectify_ms = 0.0;
  double rectify_cpu_ms = 0.0;  // CPU time of the process over rectify_ms (both threads, OpenCV's pool)
  double he_ms = 0.0;
  double extract_ms = 0.0;
  double stereo_ms = 0.0;
  double tracking_ms = 0.0;
  double tracking_cpu_ms = 0.0;  // CPU time of the tracking call on its own thread: its critical path on an idle core
  double tracking_process_cpu_ms = 0.0;  // ... of the process over it: with the tracker's worker's share
  double total_ms = 0.0;                 // all of the above plus feature bookkeeping (image decoding excluded)
  double cpu_ms = 0.0;  // CPU time of the process (both threads) over total_ms: the work, not the waiting
};

struct OfflineRun {
  PinholeStereo camera;
  std::vector<FrameRecord> frames;
  int keyframes = 0;
  int map_points = 0;
  // The atlas: keyframes of each map, and point observations by a keyframe of another map (0: the maps
  // are a partition).
  std::map<MapId, int> keyframes_per_map;
  int cross_map_observations = 0;
  // Hand-offs between the feature pipeline's two threads over the run, and how many of them found the
  // other thread asleep (a futex wake-up).
  std::uint64_t hand_offs = 0;
  std::uint64_t sleeping_hand_offs = 0;
  bool threads_pinned = false;  // the pipeline's two threads on two CPUs (Pipeline.pinThreads)

  int tracked_frames() const;
};

// Throws std::runtime_error (one line naming the file) on unreadable calibration or images.
OfflineRun run_offline(const EurocSequence& sequence, const OfflineRunOptions& options);

// Adds N(0, sigma_px^2) to the disparity of every stereo feature (u_right and depth follow); a
// disparity that falls to or below kMinNoisyDisparityPx loses its stereo match. Same seed, same noise.
// Returns the number of matches lost that way.
inline constexpr float kMinNoisyDisparityPx = 0.5f;
int add_disparity_noise(StereoFeatures& features, const PinholeStereo& camera, double sigma_px, std::uint64_t seed);

// Adds `offset` to k1 of both cameras. Throws std::invalid_argument (naming the camera) when a camera
// has no radial distortion coefficients (pre-rectified input).
void apply_k1_offset(StereoCalibration& calibration, double offset);

// Drops the stereo match of every feature whose match in `right_rect` (8-bit grey, rectified: the
// pixel nearest (u_right, v)) is brighter than `level`. Returns the number dropped.
int drop_stereo_right_above(StereoFeatures& features, const cv::Mat& right_rect, int level);

struct AteResult {
  double rmse_m = 0.0;
  double max_m = 0.0;
  int pairs = 0;
};
// Absolute trajectory error of the tracked frames after SE(3) Umeyama alignment (no scale).
std::optional<AteResult> compute_ate_se3(const OfflineRun& run);

// The KITTI devkit's drift (heslam-eval kitti, alignment none) of the tracked frames against the ground
// truth, paired by the frame's index in the run; nullopt without ground truth or below 100 m of path.
std::optional<eval::KittiResult> compute_kitti_drift(const OfflineRun& run);

// Summed distance between consecutive tracked positions.
double tracked_path_length_m(const OfflineRun& run);

// TUM format (stamp_s tx ty tz qx qy qz qw), tracked frames only: lost frames are not invented.
void write_tum_trajectory(const std::filesystem::path& path, const OfflineRun& run);

}  // namespace heslam::bench

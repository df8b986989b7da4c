// A synthetic stereo sequence: the API tests and tools use to render frames in memory.
//
//   SequenceRenderer renderer(load_preset(find_preset("room")), {.seed = 3, .frames = 20});
//   SynthFrame f = renderer.render_frame(0);   // f.left, f.right (CV_8U), f.T_wc_left, f.stamp_ns
//
// The rig: body frame B (x forward, y left, z up) follows the trajectory; the left camera (cam0)
// looks along body x, the right camera (cam1) sits baseline_m along the left camera's +x axis.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/imu/preintegration.hpp"
#include "tools/synth/camera_rays.hpp"
#include "tools/synth/photometry.hpp"
#include "tools/synth/preset.hpp"
#include "tools/synth/renderer.hpp"
#include "tools/synth/scene_builders.hpp"
#include "tools/synth/trajectory.hpp"

namespace heslam::synth {

struct RenderOptions {
  std::uint64_t seed = 1;        // trajectory jitter, oscillation phases and sensor noise
  int frames = 0;                // 0 = the preset's frame count
  bool apply_distortion = true;  // false renders ideal pinhole images even if the preset has distortion
  bool events = true;            // false switches the photometric events off (reference renders)
  int threads = 1;               // 1 or 2: left and right images rendered concurrently (same bytes)
  // --imu: a C2 motion (Trajectory's smooth mode; the images differ from a render without it) and,
  // in the EuRoC layout, mav0/imu0/ with the readings of an IMU at the body (imu_synth.hpp).
  bool imu = false;
  bool imu_noise_free = false;  // --imu-noise-free: exact readings (the sensor.yaml still names the model)
  ImuNoise imu_noise{};         // --imu-noise FILE: a sensor.yaml's; default the EuRoC ADIS16448's
  double imu_rate_hz = 200.0;
};

struct SynthFrame {
  int index = 0;
  std::int64_t stamp_ns = 0;
  double t_s = 0.0;  // seconds since the first frame
  Pose3 T_wb = Pose3::Identity();
  Pose3 T_wc_left = Pose3::Identity();
  Pose3 T_wc_right = Pose3::Identity();
  PhotometricState photometry;
  cv::Mat left, right;  // CV_8U
};

// First frame's timestamp (2020-09-13T12:26:40Z), so stamps look like real EuRoC nanosecond stamps.
inline constexpr std::int64_t kFirstStampNs = 1600000000000000000;

class SequenceRenderer {
 public:
  SequenceRenderer(const Preset& preset, const RenderOptions& options);
  ~SequenceRenderer();
  SequenceRenderer(const SequenceRenderer&) = delete;
  SequenceRenderer& operator=(const SequenceRenderer&) = delete;

  int num_frames() const { return num_frames_; }
  double time_s(int index) const { return index / preset_.camera.rate_hz; }
  std::int64_t stamp_ns(int index) const;
  Pose3 T_wb(int index) const { return trajectory_.T_wb(time_s(index)); }
  Pose3 T_wc_left(int index) const { return T_wb(index) * T_BS_left_; }

  SynthFrame render_frame(int index);
  // Noise-free radiance and depth (left camera) for geometry tests.
  void render_radiance_left(int index, cv::Mat& radiance, cv::Mat* depth_m);

  const Preset& preset() const { return preset_; }
  const RenderOptions& options() const { return options_; }
  const Scene& scene() const { return built_.scene; }
  const Trajectory& trajectory() const { return trajectory_; }
  const CameraRays& rays() const { return rays_; }
  bool distortion_applied() const { return rays_.distorted(); }
  Pose3 T_BS_left() const { return T_BS_left_; }    // left camera -> body
  Pose3 T_BS_right() const { return T_BS_right_; }  // right camera -> body
  // The ideal rectified model (exact when no distortion is applied).
  PinholeStereo pinhole_stereo() const;

 private:
  void render_camera(int camera, const SynthFrame& frame, cv::Mat& out);

  Preset preset_;
  RenderOptions options_;
  BuiltScene built_;
  Trajectory trajectory_;
  CameraRays rays_;
  Sensor sensor_;
  Pose3 T_BS_left_, T_BS_right_;
  std::vector<std::unique_ptr<Renderer>> renderers_;  // one per camera: they own scratch buffers
  int num_frames_ = 0;
};

// A whole sequence in memory (for short sequences in tests).
struct SynthSequence {
  Preset preset;
  RenderOptions options;
  std::vector<SynthFrame> frames;
  std::vector<MarkerCorner> marker_corners;
  Pose3 T_BS_left = Pose3::Identity();
  Pose3 T_BS_right = Pose3::Identity();
  PinholeStereo pinhole;
};

SynthSequence render(const Preset& preset, const RenderOptions& options);

}  // namespace heslam::synth

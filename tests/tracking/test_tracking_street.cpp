// The tracker at car speed: the synthetic `street` drive (KITTI 00-02 camera, 10 Hz, up to 9 m/s)
// rendered by heslam-synth, written in the EuRoC layout and run through the offline frontend
// (rectify -> HE -> ORB -> stereo -> track) with config/frontend/kitti.yaml's values. The first 210
// frames accelerate from rest, drive 150 m down the first street and turn 90 degrees left at its end
// (frames ~163-200). Known answers: every frame tracked, drift against the generator's exact poses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "test_support.hpp"
#include "tools/bench/frontend_offline/offline_run.hpp"
#include "tools/synth/preset.hpp"
#include "tools/synth/sequence.hpp"
#include "tools/synth/writers.hpp"

namespace heslam {
namespace {

// Through the end of the first corner (the heading reaches 90 degrees at frame ~200).
constexpr int kFirstCornerFrames = 210;

bench::OfflineRun run_street_excerpt(const std::filesystem::path& dir, int frames) {
  synth::SequenceRenderer renderer(synth::load_preset(synth::find_preset("street")),
                                   {.seed = 1, .frames = frames, .apply_distortion = false, .threads = 2});
  synth::write_sequence(renderer, synth::OutputFormat::kEuroc, dir);
  bench::OfflineRunOptions options;
  options.pipeline.orb.features = 2000;               // config/frontend/kitti.yaml
  options.tracker.max_frames_between_keyframes = 10;  // config/frontend/kitti.yaml: = camera fps
  return bench::run_offline(bench::load_euroc_sequence(dir), options);
}

double heading_deg(const Pose3& T_wc) {
  // Camera z (optical axis) projected on the ground plane (world z up).
  const Eigen::Vector3d forward = T_wc.rotation().col(2);
  return std::atan2(forward.y(), forward.x()) * 180.0 / 3.14159265358979323846;
}

// Before the street layout fix the drive went through a facade at frame 21 and every
// later frame was lost.
TEST(TrackingStreet, FirstCornerEveryFrameTrackedWithKittiDriftBelowOnePointFivePercent) {
  test::ScratchDir scratch("tracking_street");
  const bench::OfflineRun run = run_street_excerpt(scratch.path() / "street", kFirstCornerFrames);
  ASSERT_EQ(static_cast<int>(run.frames.size()), kFirstCornerFrames);
  ASSERT_TRUE(run.frames.front().T_wc_truth && run.frames.back().T_wc_truth);

  // The excerpt does contain the corner: the true heading turns by about 90 degrees.
  const double turn_deg = heading_deg(*run.frames.back().T_wc_truth) - heading_deg(*run.frames.front().T_wc_truth);
  EXPECT_NEAR(turn_deg, 90.0, 5.0);

  const auto ate = bench::compute_ate_se3(run);
  const auto drift = bench::compute_kitti_drift(run);
  std::printf(
      "[ figures  ] street first %d frames: %d tracked, %d keyframes, ATE %.3f m, KITTI drift %.2f %% "
      "(%zu sub-sequences), %.3f deg/100 m\n",
      kFirstCornerFrames, run.tracked_frames(), run.keyframes, ate ? ate->rmse_m : -1.0,
      drift ? drift->translation_error_percent : -1.0, drift ? drift->segments.size() : 0,
      drift ? drift->rotation_error_deg_per_100m : -1.0);
  EXPECT_EQ(run.tracked_frames(), kFirstCornerFrames);
  ASSERT_TRUE(drift.has_value());
  // The target (ORB-SLAM2 publishes 0.4-1.4 % on real KITTI 00-10 stereo).
  EXPECT_LT(drift->translation_error_percent, 1.5);
}

}  // namespace
}  // namespace heslam

// The atlas in the tracker: heslam-synth's corridor_jump (exact ground truth) carries the camera
// 9 m further along its path between frames 119 and 120, round the corner into corridor it has never seen.
// Tracking is lost at the jump and no relocalization can succeed; once the loss is as old as the
// rule's 1 s (frame stamps), the tracker starts a new map on that very frame, from the last pose it
// had. Every later frame has a pose in the new map, whose motion is the ground truth's, and no point
// of one map is observed by a keyframe of the other.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "relocalization_test_vocabulary.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"
#include "tools/bench/frontend_offline/offline_run.hpp"

namespace heslam {
namespace {

constexpr int kJump = 120;       // corridor_jump: trajectory.teleport_at_s 6.0 at 20 Hz
constexpr int kRuleFrames = 20;  // atlas.new_map_after_s 1.0 at 20 Hz
constexpr int kMaxFramesAfterRule = 3;
constexpr int kFramesInNewMap = 60;
constexpr int kFrames = kJump + kRuleFrames + kMaxFramesAfterRule + kFramesInNewMap;
constexpr std::int64_t kNewMapAfterNs = 1'000'000'000;
// The new map's motion against the ground truth's over its first 3 s (exact synthetic geometry;
// measured 17.1 mm).
constexpr double kMaxRelativeError_m = 0.025;

const bench::FrameRecord& frame_at(const bench::OfflineRun& run, int k) {
  return run.frames[static_cast<std::size_t>(k)];
}

TEST(Atlas, CorridorJumpStartsANewMapOnceTheLossIsOneSecondOld) {
  const test::ScratchDir scratch("atlas_teleport");
  const auto rendered = scratch.path() / "corridor_jump";
  ASSERT_EQ(test::render_synth("corridor_jump", kFrames, rendered, scratch.path()), "");
  const auto sequence = bench::load_euroc_sequence(rendered);
  bench::OfflineRunOptions options;
  options.vocabulary = test::relocalization_test_vocabulary();  // relocalization searches every map with it
  options.tracker.new_map_after_ns = kNewMapAfterNs;
  const bench::OfflineRun run = bench::run_offline(sequence, options);
  ASSERT_EQ(run.frames.size(), static_cast<std::size_t>(kFrames));

  for (int k = 0; k < kJump; ++k) {
    ASSERT_EQ(frame_at(run, k).state, TrackingState::kOk) << "frame " << k;
    ASSERT_EQ(frame_at(run, k).map_id, kFirstMapId) << "frame " << k;
  }
  int lost_at = -1;
  for (int k = kJump; k < kFrames && lost_at < 0; ++k) {
    if (frame_at(run, k).state != TrackingState::kOk) lost_at = k;
  }
  ASSERT_GE(lost_at, kJump) << "the teleport was never lost";
  EXPECT_LE(lost_at, kJump + 1) << "the teleport was tracked";
  int started_at = -1;
  for (int k = lost_at; k < kFrames && started_at < 0; ++k) {
    if (frame_at(run, k).state == TrackingState::kOk) started_at = k;
  }
  ASSERT_GE(started_at, 0) << "no frame after the loss has a pose";
  const int allowed_at = lost_at + kRuleFrames;  // the first frame whose stamp is 1 s after the loss
  EXPECT_GE(started_at, allowed_at) << "a new map before the rule allowed it";
  EXPECT_LE(started_at, allowed_at + kMaxFramesAfterRule);
  EXPECT_EQ(frame_at(run, started_at).method, TrackingMethod::kInitialization);
  EXPECT_EQ(frame_at(run, started_at).map_id, 1u);
  // Its origin is the last pose the tracker had: the trajectory goes on from there.
  EXPECT_EQ(frame_at(run, started_at).T_wc.matrix(), frame_at(run, lost_at - 1).T_wc.matrix());

  ASSERT_TRUE(frame_at(run, started_at).T_wc_truth.has_value());
  const Pose3 T_start = frame_at(run, started_at).T_wc;
  const Pose3 T_start_truth = *frame_at(run, started_at).T_wc_truth;
  double max_error_m = 0.0;
  for (int k = started_at; k < kFrames; ++k) {
    const bench::FrameRecord& frame = frame_at(run, k);
    ASSERT_EQ(frame.state, TrackingState::kOk) << "frame " << k << " has no pose in the new map";
    ASSERT_EQ(frame.map_id, 1u) << "frame " << k;
    ASSERT_TRUE(frame.T_wc_truth.has_value());
    const Eigen::Vector3d moved = (T_start.inverse() * frame.T_wc).translation();
    const Eigen::Vector3d moved_truth = (T_start_truth.inverse() * *frame.T_wc_truth).translation();
    max_error_m = std::max(max_error_m, (moved - moved_truth).norm());
  }
  EXPECT_LT(max_error_m, kMaxRelativeError_m);
  ASSERT_EQ(run.keyframes_per_map.size(), 2u);
  EXPECT_GT(run.keyframes_per_map.at(1), 1);
  EXPECT_EQ(run.cross_map_observations, 0);
  std::printf(
      "[ figures  ] corridor_jump: lost at frame %d, new map 1 at frame %d (the rule allowed frame %d), "
      "%d + %d keyframes, largest error of the new map's motion %.2f mm over %d frames\n",
      lost_at, started_at, allowed_at, run.keyframes_per_map.at(kFirstMapId), run.keyframes_per_map.at(1),
      max_error_m * 1e3, kFrames - started_at);
}

// 0 (atlas.new_map_after_s 0): never a new map, the frames stay lost as before the atlas.
TEST(Atlas, ZeroNeverStartsANewMap) {
  const test::ScratchDir scratch("atlas_teleport_off");
  const auto rendered = scratch.path() / "corridor_jump";
  constexpr int kFramesOff = kJump + kRuleFrames + 2 * kMaxFramesAfterRule;
  ASSERT_EQ(test::render_synth("corridor_jump", kFramesOff, rendered, scratch.path()), "");
  bench::OfflineRunOptions options;
  options.vocabulary = test::relocalization_test_vocabulary();
  options.tracker.new_map_after_ns = 0;
  const bench::OfflineRun run = bench::run_offline(bench::load_euroc_sequence(rendered), options);
  ASSERT_EQ(run.frames.size(), static_cast<std::size_t>(kFramesOff));
  for (int k = kJump + 1; k < kFramesOff; ++k) {
    EXPECT_NE(frame_at(run, k).state, TrackingState::kOk) << "frame " << k;
  }
  EXPECT_EQ(run.keyframes_per_map.size(), 1u);
}

}  // namespace
}  // namespace heslam

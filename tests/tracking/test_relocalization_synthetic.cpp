// Relocalization in the old part of a map, "teleported camera": a synthetic corridor_loop
// excerpt (exact ground truth) whose frames 0-429 are the walk's first 21.5 s and whose frames from
// 430 on show the walk's frames 20-39 again, with no black frame between: between two shots the
// camera is carried back to where it was 20.5 s earlier, on the other side of the ring. The motion
// model and the reference keyframe fail at the jump (the tracker declares the frame lost); the place
// is far older than the newest keyframes, so only the keyframe database finds it: with it the camera
// is relocalized within 3 frames at the first pass's poses and the ground truth (2 cm); without a
// vocabulary (the newest-keyframes path) it stays lost.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "relocalization_test_vocabulary.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"
#include "tools/bench/frontend_offline/kidnapped_copy.hpp"
#include "tools/bench/frontend_offline/offline_run.hpp"

namespace heslam {
namespace {

constexpr int kJump = 430;         // the first frame after the teleport (21.5 s at 20 Hz)
constexpr int kReplaySource = 20;  // it shows the walk's frame 20 (1.0 s): 20.5 s earlier
constexpr int kReplayedFrames = 20;
constexpr int kFrames = kJump + kReplayedFrames;
constexpr int kMaxFramesToRelocalize = 3;
constexpr double kMaxPositionError_m = 0.02;

const bench::FrameRecord& frame_at(const bench::OfflineRun& run, int k) {
  return run.frames[static_cast<std::size_t>(k)];
}

TEST(KidnappedCamera, CorridorLoopTeleportedTwentySecondsBackIsRelocalizedOnlyWithTheDatabase) {
  const auto vocabulary = test::relocalization_test_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "no default vocabulary and no euroc_v101_head to train one on";
  const test::ScratchDir scratch("teleport_corridor");
  const auto rendered = scratch.path() / "corridor_loop";
  const auto teleported = scratch.path() / "teleported";
  ASSERT_EQ(test::render_synth("corridor_loop", kJump, rendered, scratch.path()), "");
  ASSERT_EQ(bench::write_kidnapped_copy(rendered, teleported,
                                        bench::KidnapPlan{kJump, kJump, kReplaySource, kReplayedFrames}),
            kFrames);

  // The two runs are independent and single-threaded: one per core.
  const auto sequence = bench::load_euroc_sequence(teleported);
  bench::OfflineRunOptions with_database;
  with_database.vocabulary = vocabulary;
  bench::OfflineRunOptions newest_keyframes_only;
  newest_keyframes_only.max_frames = kJump + 2 * kMaxFramesToRelocalize;
  auto without_run =
      std::async(std::launch::async, [&] { return bench::run_offline(sequence, newest_keyframes_only); });
  const bench::OfflineRun run = bench::run_offline(sequence, with_database);
  const bench::OfflineRun without = without_run.get();
  ASSERT_EQ(run.frames.size(), static_cast<std::size_t>(kFrames));

  for (int k = 0; k < kJump; ++k) ASSERT_EQ(frame_at(run, k).state, TrackingState::kOk) << "frame " << k;
  EXPECT_NE(frame_at(run, kJump).state, TrackingState::kOk) << "the jump was tracked by the motion model";
  int relocalized_at = -1;
  for (int k = kJump; k < kFrames && relocalized_at < 0; ++k) {
    if (frame_at(run, k).state == TrackingState::kOk) relocalized_at = k;
  }
  ASSERT_GE(relocalized_at, kJump) << "never relocalized";
  EXPECT_EQ(frame_at(run, relocalized_at).method, TrackingMethod::kRelocalization);
  EXPECT_LE(relocalized_at, kJump + kMaxFramesToRelocalize);

  // The tracker's world is the first camera's: the ground truth in it is T_truth(0)^-1 T_truth(k).
  ASSERT_TRUE(frame_at(run, 0).T_wc_truth.has_value());
  const Pose3 T_first_truth = frame_at(run, 0).T_wc_truth->inverse();
  double max_to_first_pass_m = 0.0;
  double max_to_truth_m = 0.0;
  for (int k = relocalized_at; k < kFrames; ++k) {
    const bench::FrameRecord& frame = frame_at(run, k);
    const int image = kReplaySource + k - kJump;
    ASSERT_EQ(frame.state, TrackingState::kOk) << "frame " << k << " lost after the relocalization";
    ASSERT_TRUE(frame.T_wc_truth.has_value()) << "frame " << k;
    const double to_first_pass_m = (frame.T_wc.translation() - frame_at(run, image).T_wc.translation()).norm();
    const double to_truth_m = (frame.T_wc.translation() - (T_first_truth * *frame.T_wc_truth).translation()).norm();
    max_to_first_pass_m = std::max(max_to_first_pass_m, to_first_pass_m);
    max_to_truth_m = std::max(max_to_truth_m, to_truth_m);
    EXPECT_LT(to_first_pass_m, kMaxPositionError_m) << "frame " << k << " (image of frame " << image << ")";
    EXPECT_LT(to_truth_m, kMaxPositionError_m) << "frame " << k << " (image of frame " << image << ")";
  }

  int relocalized_without = 0;
  for (int k = kJump; k < static_cast<int>(without.frames.size()); ++k) {
    relocalized_without += frame_at(without, k).state == TrackingState::kOk ? 1 : 0;
  }
  std::printf(
      "[ figures  ] teleported corridor_loop: with the database relocalized at frame %d (%d frames lost), "
      "relocalization %.1f ms (CPU %.1f ms), largest distance to the first pass %.2f mm, to the ground "
      "truth %.2f mm; newest keyframes only: %d of frames %d-%zu tracked\n",
      relocalized_at, relocalized_at - kJump, frame_at(run, relocalized_at).tracking_ms,
      frame_at(run, relocalized_at).tracking_cpu_ms, max_to_first_pass_m * 1e3, max_to_truth_m * 1e3,
      relocalized_without, kJump, without.frames.size() - 1);
  EXPECT_EQ(relocalized_without, 0) << "the newest keyframes relocalized a place seen 20 s before";
}

}  // namespace
}  // namespace heslam

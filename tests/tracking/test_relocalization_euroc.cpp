// Relocalization on real data, "kidnapped camera": a copy of the hand-held MH01 clip where frames
// 60-79 are black and frames 80-159 show frames 0-79 again, so the camera reappears where it was 4 s
// earlier. The tracker (with a vocabulary and its keyframe database) must relocalize within 3 frames
// of the first valid image, at the poses the first pass had at the same images.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>

#include "relocalization_test_vocabulary.hpp"
#include "test_support.hpp"
#include "tools/bench/frontend_offline/kidnapped_copy.hpp"
#include "tools/bench/frontend_offline/offline_run.hpp"

namespace heslam {
namespace {

constexpr int kFirstValidImage = 80;       // the first frame after the black ones
constexpr int kMaxFramesToRelocalize = 3;  // relocalized at frame 83 at the latest
constexpr double kMaxPositionError_m = 0.02;

TEST(KidnappedCamera, Mh01RelocalizedWithinThreeFramesAtTheFirstPassPoses) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  HESLAM_REQUIRE_SHARED_DATA("euroc_v101_head");
  const test::ScratchDir scratch("kidnapped_mh01");
  const auto source = test::shared_dataset("euroc_mh01_handheld");
  ASSERT_EQ(bench::write_kidnapped_copy(source, scratch.path(), bench::KidnapPlan{60, 80, 0}), 160);

  bench::OfflineRunOptions options;
  options.vocabulary = test::relocalization_test_vocabulary();
  const bench::OfflineRun first_pass = bench::run_offline(bench::load_euroc_sequence(source), [&] {
    bench::OfflineRunOptions o = options;
    o.max_frames = 80;
    return o;
  }());
  const bench::OfflineRun run = bench::run_offline(bench::load_euroc_sequence(scratch.path()), options);
  ASSERT_EQ(run.frames.size(), 160u);
  ASSERT_EQ(first_pass.tracked_frames(), 80);

  for (int k = 0; k < 60; ++k)
    EXPECT_EQ(run.frames[static_cast<std::size_t>(k)].state, TrackingState::kOk) << "frame " << k;
  for (int k = 60; k < kFirstValidImage; ++k) {
    EXPECT_NE(run.frames[static_cast<std::size_t>(k)].state, TrackingState::kOk) << "black frame " << k;
  }
  int relocalized_at = -1;
  for (int k = kFirstValidImage; k < 160 && relocalized_at < 0; ++k) {
    if (run.frames[static_cast<std::size_t>(k)].state == TrackingState::kOk) relocalized_at = k;
  }
  ASSERT_GE(relocalized_at, kFirstValidImage) << "never relocalized";
  EXPECT_EQ(run.frames[static_cast<std::size_t>(relocalized_at)].method, TrackingMethod::kRelocalization);
  EXPECT_LE(relocalized_at, kFirstValidImage + kMaxFramesToRelocalize);

  double max_error_m = 0.0;
  int tracked_after = 0;
  for (int k = relocalized_at; k < 160; ++k) {
    const bench::FrameRecord& frame = run.frames[static_cast<std::size_t>(k)];
    if (frame.state != TrackingState::kOk) continue;
    ++tracked_after;
    const bench::FrameRecord& earlier = first_pass.frames[static_cast<std::size_t>(k - kFirstValidImage)];
    const double error_m = (frame.T_wc.translation() - earlier.T_wc.translation()).norm();
    max_error_m = std::max(max_error_m, error_m);
    EXPECT_LT(error_m, kMaxPositionError_m) << "frame " << k << " (image of frame " << k - kFirstValidImage << ")";
  }
  std::printf(
      "[ figures  ] kidnapped MH01: relocalized at frame %d (%d frames lost after the black ones), "
      "relocalization %.1f ms, %d/%d frames tracked after it, largest distance to the first pass %.2f mm\n",
      relocalized_at, relocalized_at - kFirstValidImage,
      run.frames[static_cast<std::size_t>(relocalized_at)].tracking_ms, tracked_after, 160 - relocalized_at,
      max_error_m * 1e3);
  EXPECT_EQ(tracked_after, 160 - relocalized_at);
}

}  // namespace
}  // namespace heslam

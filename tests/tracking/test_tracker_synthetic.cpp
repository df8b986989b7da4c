// The tracker on a synthetic stereo world with known trajectory: every frame tracked with small error,
// bit-identical reruns, no pose published for garbage frames, relocalization after a jump.
#include <gtest/gtest.h>

#include <cstdio>

#include "components/core/tracking/tracker.hpp"
#include "synthetic_scene.hpp"

namespace heslam {
namespace {

constexpr int kFrames = 120;
constexpr std::int64_t kFramePeriodNs = 50'000'000;

struct TrackerRun {
  std::vector<TrackResult> results;
  int keyframes = 0;
};

TrackerRun run_tracker(const std::vector<test::SyntheticPoint>& points, int frames,
                       const TrackerOptions& options = TrackerOptions{}) {
  const PinholeStereo camera = test::synthetic_camera();
  Tracker tracker(camera, options);
  TrackerRun run;
  for (int k = 0; k < frames; ++k) {
    StereoFeatures f = test::make_frame(points, camera, test::trajectory_pose(k), 1000 + static_cast<std::uint64_t>(k));
    run.results.push_back(tracker.track(k * kFramePeriodNs, static_cast<std::uint64_t>(k), std::move(f)));
  }
  run.keyframes = static_cast<int>(tracker.local_map().keyframes.size());
  return run;
}

// Ground truth re-expressed in the tracker's world (the first camera).
Pose3 truth_in_first_camera(int k) { return test::trajectory_pose(0).inverse() * test::trajectory_pose(k); }

TEST(TrackerSynthetic, TracksEveryFrameWithSmallError) {
  const auto points = test::make_points(4000, 17);
  const TrackerRun run = run_tracker(points, kFrames);
  ASSERT_EQ(run.results.front().state, TrackingState::kOk);
  ASSERT_TRUE(run.results.front().new_keyframe.has_value());
  double max_translation_error = 0.0;
  double max_rotation_error = 0.0;
  for (int k = 0; k < kFrames; ++k) {
    const TrackResult& r = run.results[static_cast<std::size_t>(k)];
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    EXPECT_GE(r.tracked_points, 100) << "frame " << k;
    max_translation_error =
        std::max(max_translation_error, (r.T_wc.translation() - truth_in_first_camera(k).translation()).norm());
    max_rotation_error = std::max(max_rotation_error, test::rotation_error_deg(r.T_wc, truth_in_first_camera(k)));
  }
  // 0.3 px noise, 2-6 m depth, 0.11 m baseline: a stereo point's depth is off by up to ~10 cm and
  // biased outwards (E[1/disparity] > 1/E[disparity]); without local BA these map errors are the pose
  // error. Bound: 1 % of the path (heslam's synthetic VO target), 0.35 degree.
  double path_m = 0.0;
  for (int k = 1; k < kFrames; ++k) {
    path_m += (truth_in_first_camera(k).translation() - truth_in_first_camera(k - 1).translation()).norm();
  }
  std::printf("[ figures  ] synthetic: path %.2f m, max error %.1f mm / %.3f deg, %d keyframes\n", path_m,
              max_translation_error * 1e3, max_rotation_error, run.keyframes);
  EXPECT_LT(max_translation_error, 0.01 * path_m);
  EXPECT_LT(max_rotation_error, 0.35);
  EXPECT_GE(run.keyframes, 3);
  EXPECT_LE(run.keyframes, kFrames / 2);
}

TEST(TrackerSynthetic, TwoRunsAreBitIdentical) {
  const auto points = test::make_points(3000, 23);
  const TrackerRun a = run_tracker(points, 60);
  const TrackerRun b = run_tracker(points, 60);
  ASSERT_EQ(a.results.size(), b.results.size());
  for (std::size_t k = 0; k < a.results.size(); ++k) {
    EXPECT_EQ(a.results[k].T_wc.matrix(), b.results[k].T_wc.matrix()) << "frame " << k;
    EXPECT_EQ(a.results[k].tracked_points, b.results[k].tracked_points) << "frame " << k;
  }
  EXPECT_EQ(a.keyframes, b.keyframes);
}

// Inside the frontend the mapper owns observations and covisibility; until its state arrives the
// tracker must still track from the keyframes and points it inserted itself.
TEST(TrackerSynthetic, TracksWithoutMaintainingTheMap) {
  const auto points = test::make_points(4000, 17);
  TrackerOptions options;
  options.maintain_map = false;
  const TrackerRun run = run_tracker(points, kFrames, options);
  for (int k = 0; k < kFrames; ++k) {
    const TrackResult& r = run.results[static_cast<std::size_t>(k)];
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    EXPECT_LT((r.T_wc.translation() - truth_in_first_camera(k).translation()).norm(), 0.05) << "frame " << k;
  }
  EXPECT_GE(run.keyframes, 2);
}

TEST(TrackerSynthetic, WaitsForEnoughStereoPointsToInitialize) {
  const PinholeStereo camera = test::synthetic_camera();
  Tracker tracker(camera, TrackerOptions{});
  const auto sparse = test::make_points(300, 5);  // far fewer than 500 keypoints in view
  const TrackResult r = tracker.track(0, 0, test::make_frame(sparse, camera, Pose3::Identity(), 1));
  EXPECT_EQ(r.state, TrackingState::kNotInitialized);
  EXPECT_FALSE(r.pose_valid());
  EXPECT_TRUE(tracker.local_map().keyframes.empty());
}

TEST(TrackerSynthetic, InconsistentFeaturesAreRejectedWithoutStateChange) {
  const PinholeStereo camera = test::synthetic_camera();
  const auto points = test::make_points(3000, 41);
  Tracker tracker(camera, TrackerOptions{});
  ASSERT_EQ(tracker.track(0, 0, test::make_frame(points, camera, test::trajectory_pose(0), 1)).state,
            TrackingState::kOk);
  StereoFeatures bad = test::make_frame(points, camera, test::trajectory_pose(1), 2);
  bad.depth_m.pop_back();
  EXPECT_THROW(tracker.track(kFramePeriodNs, 1, bad), std::invalid_argument);
  StereoFeatures bad_octave = test::make_frame(points, camera, test::trajectory_pose(1), 2);
  bad_octave.keypoints[3].octave = 99;
  EXPECT_THROW(tracker.track(kFramePeriodNs, 1, bad_octave), std::invalid_argument);
  const TrackResult next =
      tracker.track(kFramePeriodNs, 1, test::make_frame(points, camera, test::trajectory_pose(1), 2));
  EXPECT_EQ(next.state, TrackingState::kOk);
  EXPECT_LT((next.T_wc.translation() - truth_in_first_camera(1).translation()).norm(), 0.01);
}

TEST(TrackerSynthetic, GarbageFrameIsLostThenRelocalizesAfterAJump) {
  const PinholeStereo camera = test::synthetic_camera();
  const auto points = test::make_points(4000, 31);
  Tracker tracker(camera, TrackerOptions{});
  int k = 0;
  for (; k < 40; ++k) {
    const TrackResult r =
        tracker.track(k * kFramePeriodNs, static_cast<std::uint64_t>(k),
                      test::make_frame(points, camera, test::trajectory_pose(k), 500 + static_cast<std::uint64_t>(k)));
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
  }
  // A frame of pure clutter (e.g. the lens covered): no pose may be published.
  test::SyntheticFrameOptions clutter;
  clutter.clutter_keypoints = 800;
  const TrackResult lost = tracker.track(k * kFramePeriodNs, static_cast<std::uint64_t>(k),
                                         test::make_frame({}, camera, Pose3::Identity(), 99, clutter));
  ++k;
  EXPECT_EQ(lost.state, TrackingState::kLost);
  EXPECT_FALSE(lost.pose_valid());
  EXPECT_FALSE(lost.new_keyframe.has_value());

  // The camera reappears 10 frames later on the trajectory: relocalized against a recent keyframe.
  const int jump = k + 10;
  const TrackResult back = tracker.track(jump * kFramePeriodNs, static_cast<std::uint64_t>(k),
                                         test::make_frame(points, camera, test::trajectory_pose(jump), 77));
  ASSERT_EQ(back.state, TrackingState::kOk);
  EXPECT_EQ(back.method, TrackingMethod::kRelocalization);
  EXPECT_LT((back.T_wc.translation() - truth_in_first_camera(jump).translation()).norm(), 0.02);
  EXPECT_LT(test::rotation_error_deg(back.T_wc, truth_in_first_camera(jump)), 0.2);
}

// A restarted frontend: a new tracker handed the map of the first one resumes in it. Its first frame
// is relocalized in that map (the same world frame, not a new origin), and its new keyframe ids
// continue past the map's.
TEST(TrackerSynthetic, ResumeInMapRelocalizesInTheOldMapAndContinuesIds) {
  const PinholeStereo camera = test::synthetic_camera();
  const auto points = test::make_points(4000, 31);
  Tracker first(camera, TrackerOptions{});
  int k = 0;
  for (; k < 40; ++k) {
    ASSERT_EQ(
        first
            .track(k * kFramePeriodNs, static_cast<std::uint64_t>(k),
                   test::make_frame(points, camera, test::trajectory_pose(k), 500 + static_cast<std::uint64_t>(k)))
            .state,
        TrackingState::kOk);
  }
  const KeyframeId last_id = first.local_map().keyframes.rbegin()->first;

  Tracker restarted(camera, TrackerOptions{});
  EXPECT_FALSE(restarted.resume_in_map());  // nothing to resume in
  restarted.local_map() = first.local_map();
  ASSERT_TRUE(restarted.resume_in_map());
  EXPECT_EQ(restarted.state(), TrackingState::kLost);
  EXPECT_FALSE(restarted.resume_in_map());  // once

  const TrackResult back = restarted.track(k * kFramePeriodNs, static_cast<std::uint64_t>(k),
                                           test::make_frame(points, camera, test::trajectory_pose(k), 77));
  ASSERT_EQ(back.state, TrackingState::kOk);
  EXPECT_EQ(back.method, TrackingMethod::kRelocalization);
  EXPECT_LT((back.T_wc.translation() - truth_in_first_camera(k).translation()).norm(), 0.02);
  // Tracks on and makes keyframes with ids after the old map's.
  KeyframeId new_id = kNoId;
  for (++k; k < kFrames && new_id == kNoId; ++k) {
    const TrackResult r = restarted.track(
        k * kFramePeriodNs, static_cast<std::uint64_t>(k),
        test::make_frame(points, camera, test::trajectory_pose(k), 900 + static_cast<std::uint64_t>(k)));
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    if (r.new_keyframe) new_id = r.new_keyframe->id;
  }
  ASSERT_NE(new_id, kNoId);
  EXPECT_GT(new_id, last_id);
  EXPECT_EQ(creator_of(new_id), creator_of(last_id));
}

// A restarted frontend that knows where its previous process's last frame was (its journal): the
// next frame is tracked from that pose against its reference keyframe, no relocalization needed,
// and the tracker goes on as if never restarted.
TEST(TrackerSynthetic, ResumeInMapFromTheLastFramePoseTracksTheNextFrameDirectly) {
  const PinholeStereo camera = test::synthetic_camera();
  const auto points = test::make_points(4000, 31);
  Tracker first(camera, TrackerOptions{});
  int k = 0;
  TrackResult last;
  for (; k < 40; ++k) {
    last = first.track(k * kFramePeriodNs, static_cast<std::uint64_t>(k),
                       test::make_frame(points, camera, test::trajectory_pose(k), 500 + static_cast<std::uint64_t>(k)));
    ASSERT_EQ(last.state, TrackingState::kOk);
  }
  Tracker restarted(camera, TrackerOptions{});
  restarted.local_map() = first.local_map();
  ASSERT_TRUE(restarted.resume_in_map(LastFramePose{last.reference_kf, last.T_ref_c, last.T_wc}));
  EXPECT_EQ(restarted.state(), TrackingState::kOk);
  for (int n = 0; n < 5; ++n, ++k) {
    const TrackResult r = restarted.track(
        k * kFramePeriodNs, static_cast<std::uint64_t>(k),
        test::make_frame(points, camera, test::trajectory_pose(k), 900 + static_cast<std::uint64_t>(k)));
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    EXPECT_NE(r.method, TrackingMethod::kRelocalization) << "frame " << k;
    if (n == 0) {
      EXPECT_EQ(r.method, TrackingMethod::kReferenceKeyframe);
    }
    EXPECT_LT((r.T_wc.translation() - truth_in_first_camera(k).translation()).norm(), 0.02) << "frame " << k;
  }

  // A reference keyframe the map does not hold (it died with the old process): the map's newest
  // keyframe and the journaled world pose instead.
  Tracker without_reference(camera, TrackerOptions{});
  without_reference.local_map() = first.local_map();
  ASSERT_TRUE(without_reference.resume_in_map(LastFramePose{last.reference_kf + 1000, last.T_ref_c, last.T_wc}));
  const int next = 40;
  const TrackResult r = without_reference.track(next * kFramePeriodNs, static_cast<std::uint64_t>(next),
                                                test::make_frame(points, camera, test::trajectory_pose(next), 77));
  ASSERT_EQ(r.state, TrackingState::kOk);
  EXPECT_LT((r.T_wc.translation() - truth_in_first_camera(next).translation()).norm(), 0.02);
}

// A frontend restarted with nothing to resume from (its map file and its predecessor's map lost):
// it starts a new map, but in an id range of its own (skip_ids_through, restart n -> n << 40), so
// its first keyframe and points never reuse an id the earlier process published.
TEST(TrackerSynthetic, IdsSkippedPastARestartRangeNeverRepeatTheFirstProcesssIds) {
  const PinholeStereo camera = test::synthetic_camera();
  const auto points = test::make_points(4000, 31);
  Tracker first(camera, TrackerOptions{});
  Tracker restarted(camera, TrackerOptions{});
  constexpr std::uint64_t kRestartRange = std::uint64_t{1} << 40;
  restarted.skip_ids_through(kRestartRange, kRestartRange);
  restarted.skip_ids_through(5, 5);  // never lowers them
  const TrackResult a = first.track(0, 0, test::make_frame(points, camera, test::trajectory_pose(0), 500));
  const TrackResult b = restarted.track(0, 0, test::make_frame(points, camera, test::trajectory_pose(0), 500));
  ASSERT_TRUE(a.new_keyframe && b.new_keyframe);
  EXPECT_EQ(counter_of(a.new_keyframe->id), 1u);
  EXPECT_EQ(counter_of(b.new_keyframe->id), kRestartRange + 1);
  for (const auto& [id, point] : restarted.local_map().points) {
    EXPECT_GT(counter_of(id), kRestartRange);
    EXPECT_EQ(first.local_map().points.count(id), 0u);
  }
}

}  // namespace
}  // namespace heslam

// The stationary test (stationary_test.hpp) inside the tracker, on synthetic stereo worlds with a
// known trajectory: a still camera keeps its pose exactly, a camera turning in place keeps its centre,
// slow motion is released instead of accumulated, keyframes are never held, and a moving camera is
// never held.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>

#include "components/core/tracking/tracker.hpp"
#include "synthetic_scene.hpp"

namespace heslam {
namespace {

constexpr std::int64_t kFramePeriodNs = 50'000'000;

struct TrackedRun {
  std::vector<TrackResult> results;
  int still = 0;
  int rotating = 0;
  double path_m = 0.0;  // summed distance between consecutive estimated positions
  double max_position_error_m = 0.0;
  double max_rotation_error_deg = 0.0;
};

// Tracks `frames` frames of the camera at truth(k) (camera to world); errors in the first camera's frame.
TrackedRun track_camera(const std::function<Pose3(int)>& truth, int frames,
                        const TrackerOptions& options = TrackerOptions{}) {
  const auto points = test::make_points(4000, 17);
  const PinholeStereo camera = test::synthetic_camera();
  Tracker tracker(camera, options);
  TrackedRun r;
  for (int k = 0; k < frames; ++k) {
    StereoFeatures f = test::make_frame(points, camera, truth(k), 5000 + static_cast<std::uint64_t>(k));
    r.results.push_back(tracker.track(k * kFramePeriodNs, static_cast<std::uint64_t>(k), std::move(f)));
    const TrackResult& result = r.results.back();
    EXPECT_EQ(result.state, TrackingState::kOk) << "frame " << k;
    r.still += result.motion == FrameMotion::kStill ? 1 : 0;
    r.rotating += result.motion == FrameMotion::kRotatingInPlace ? 1 : 0;
    if (k > 0) r.path_m += (result.T_wc.translation() - r.results[r.results.size() - 2].T_wc.translation()).norm();
    const Pose3 expected = truth(0).inverse() * truth(k);
    r.max_position_error_m =
        std::max(r.max_position_error_m, (result.T_wc.translation() - expected.translation()).norm());
    r.max_rotation_error_deg = std::max(r.max_rotation_error_deg, test::rotation_error_deg(result.T_wc, expected));
  }
  return r;
}

TrackerOptions without_stationary_test() {
  TrackerOptions options;
  options.stationary_test_chi2 = 0.0;
  options.rotation_only_test_chi2 = 0.0;
  return options;
}

Pose3 still_camera(int) { return test::trajectory_pose(0); }

// Yaw about the camera's own centre, 0.05 degree per frame (1 degree a second at 20 Hz).
Pose3 turning_in_place(int k) {
  Pose3 T = test::trajectory_pose(0);
  T.linear() = T.linear() * Eigen::AngleAxisd(0.05 * M_PI / 180.0 * k, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

// Sideways creep of 0.2 mm per frame: each step is below the noise, the sum is not.
Pose3 creeping(int k) {
  Pose3 T = test::trajectory_pose(0);
  T.translation() += T.linear() * Eigen::Vector3d(0.0002 * k, 0.0, 0.0);
  return T;
}

TEST(StationaryTest, StillCameraKeepsItsPoseExactly) {
  const TrackedRun with = track_camera(still_camera, 60);
  const TrackedRun without = track_camera(still_camera, 60, without_stationary_test());
  std::printf("[ figures  ] still camera, 60 frames: path %.3f mm with the test (%d still), %.3f mm without\n",
              with.path_m * 1e3, with.still, without.path_m * 1e3);
  EXPECT_EQ(with.still, 59);
  EXPECT_EQ(with.path_m, 0.0);
  EXPECT_GT(without.path_m, 0.005);  // per-frame noise of 0.3 px adds up to millimetres of path
  EXPECT_LT(with.max_position_error_m, without.max_position_error_m + 1e-12);
}

TEST(StationaryTest, CameraTurningInPlaceKeepsItsCentre) {
  const TrackedRun with = track_camera(turning_in_place, 60);
  const TrackedRun without = track_camera(turning_in_place, 60, without_stationary_test());
  std::printf(
      "[ figures  ] turning in place, 3 degrees: path %.3f mm with the test (%d rotating, %d still), "
      "%.3f mm without; rotation error %.4f / %.4f deg\n",
      with.path_m * 1e3, with.rotating, with.still, without.path_m * 1e3, with.max_rotation_error_deg,
      without.max_rotation_error_deg);
  EXPECT_GE(with.rotating, 50);
  EXPECT_EQ(with.path_m, 0.0);  // rotating frames keep the centre, still ones the whole pose
  EXPECT_GT(without.path_m, 0.005);
  EXPECT_LT(with.max_rotation_error_deg, 0.05);  // the rotation is still followed
}

TEST(StationaryTest, SlowCreepIsReleasedNotAccumulated) {
  const int frames = 100;  // 20 mm in all
  const TrackedRun with = track_camera(creeping, frames);
  std::printf(
      "[ figures  ] creep of 0.2 mm per frame: %d still, %d rotating, max position error %.2f mm, "
      "estimated path %.1f mm of 19.8 mm\n",
      with.still, with.rotating, with.max_position_error_m * 1e3, with.path_m * 1e3);
  // Held frames lag the truth by at most what the test cannot tell apart (a few millimetres at 2-6 m),
  // never by the accumulated creep.
  EXPECT_LT(with.max_position_error_m, 0.006);
  const Pose3 last_truth = creeping(0).inverse() * creeping(frames - 1);
  EXPECT_LT((with.results.back().T_wc.translation() - last_truth.translation()).norm(), 0.006);
}

// New points are created from a keyframe's pose, so a frame that becomes a keyframe keeps its
// optimized pose. A still camera made to insert a keyframe on every frame (the "close points"
// rule forced on) would otherwise hold every one of them.
TEST(StationaryTest, KeyframesAreNeverHeld) {
  TrackerOptions options;
  options.close_tracked_needed = 1 << 30;
  options.close_untracked_enough = -1;
  const TrackedRun with = track_camera(still_camera, 20, options);
  int keyframes = 0;
  for (std::size_t k = 1; k < with.results.size(); ++k) {
    const TrackResult& r = with.results[k];
    if (!r.new_keyframe) continue;
    ++keyframes;
    EXPECT_EQ(r.motion, FrameMotion::kMoving) << "frame " << k;
    EXPECT_TRUE(r.new_keyframe->T_wc.translation() == r.T_wc.translation()) << "frame " << k;
  }
  EXPECT_EQ(keyframes, 19);
  EXPECT_EQ(with.still + with.rotating, 0);
}

TEST(StationaryTest, MovingCameraIsNeverHeld) {
  const TrackedRun with = track_camera(test::trajectory_pose, 120);
  EXPECT_EQ(with.still, 0);
  EXPECT_EQ(with.rotating, 0);
}

}  // namespace
}  // namespace heslam

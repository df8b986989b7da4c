// Keyframe decision: ORB-SLAM2's stereo rules on hand-made counts.
#include <gtest/gtest.h>

#include <cstdint>

#include <Eigen/Geometry>

#include "components/core/tracking/keyframe_decision.hpp"
#include "synthetic_scene.hpp"

namespace heslam {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A frame with `tracked` close tracked stereo points, `untracked` close untracked ones.
Frame make_counted_frame(const PinholeStereo& camera, int tracked, int untracked) {
  StereoFeatures f;
  for (int i = 0; i < tracked + untracked; ++i) {
    Keypoint kp;
    kp.u_px = static_cast<float>(10 + i % 600);
    kp.v_px = static_cast<float>(10 + i / 600);
    f.keypoints.push_back(kp);
    f.descriptors.push_back(Descriptor{});
    f.depth_m.push_back(2.f);  // close: under 35 baselines (3.85 m)
    f.u_right_px.push_back(kp.u_px - 20.f);
  }
  Frame frame(0, 0, f, camera);
  for (int i = 0; i < tracked; ++i)
    frame.point_ids[static_cast<std::size_t>(i)] = make_id(1, static_cast<std::uint64_t>(i + 1));
  return frame;
}

TEST(KeyframeDecision, FewCloseTrackedAndManyNewInserts) {
  const PinholeStereo camera = test::synthetic_camera();
  const Frame frame = make_counted_frame(camera, 60, 200);
  KeyframeDecisionInput input;
  input.frames_since_keyframe = 3;
  input.tracked_inliers = 60;
  input.keyframes_in_map = 5;
  input.reference_tracked_points = 70;  // 60 > 0.75 * 70: only the close-point rule can trigger
  const KeyframeDecision decision = decide_keyframe(frame, camera, input, TrackerOptions{});
  EXPECT_EQ(decision.tracked_close, 60);
  EXPECT_EQ(decision.untracked_close, 200);
  EXPECT_TRUE(decision.insert);
}

TEST(KeyframeDecision, WellTrackedFrameIsNotAKeyframe) {
  const PinholeStereo camera = test::synthetic_camera();
  const Frame frame = make_counted_frame(camera, 300, 50);
  KeyframeDecisionInput input;
  input.frames_since_keyframe = 3;
  input.tracked_inliers = 300;
  input.keyframes_in_map = 5;
  input.reference_tracked_points = 320;
  EXPECT_FALSE(decide_keyframe(frame, camera, input, TrackerOptions{}).insert);
}

TEST(KeyframeDecision, RatioToReferenceTriggers) {
  const PinholeStereo camera = test::synthetic_camera();
  const Frame frame = make_counted_frame(camera, 200, 50);
  KeyframeDecisionInput input;
  input.frames_since_keyframe = 3;
  input.tracked_inliers = 200;
  input.keyframes_in_map = 5;
  input.reference_tracked_points = 300;  // 200 < 0.75 * 300
  input.mapper_idle = true;
  EXPECT_TRUE(decide_keyframe(frame, camera, input, TrackerOptions{}).insert);
  input.mapper_idle = false;  // busy mapper, not a second yet, tracking not weak: wait
  EXPECT_FALSE(decide_keyframe(frame, camera, input, TrackerOptions{}).insert);
  input.frames_since_keyframe = 20;  // a second without a keyframe: insert anyway
  EXPECT_TRUE(decide_keyframe(frame, camera, input, TrackerOptions{}).insert);
}

// Cameras exposed apart: an untracked close feature whose stereo match is near a clip edge counts
// close_untracked_near_clip_weight towards the 70 needed; the tracked side and the reported counts
// stay as they are.
TEST(KeyframeDecision, UntrackedNearClipCountsByItsWeight) {
  const PinholeStereo camera = test::synthetic_camera();
  Frame frame = make_counted_frame(camera, 60, 100);  // 100 untracked close: 60 + 40 near a clip edge
  frame.features.near_clip.assign(frame.size(), 0);
  for (std::size_t i = 0; i < frame.size(); ++i) frame.features.near_clip[i] = i < 40 || i >= 100 ? 1 : 0;
  KeyframeDecisionInput input;
  input.frames_since_keyframe = 3;
  input.tracked_inliers = 60;
  input.keyframes_in_map = 5;
  input.reference_tracked_points = 70;  // 60 > 0.75 * 70: only the close-point rule can trigger
  TrackerOptions options;
  EXPECT_DOUBLE_EQ(options.close_untracked_near_clip_weight, 0.9);  // 40 + 54 = 94 > 70
  EXPECT_TRUE(decide_keyframe(frame, camera, input, options).insert);
  options.close_untracked_near_clip_weight = 1.0;
  KeyframeDecision decision = decide_keyframe(frame, camera, input, options);  // weight 1: 100 > 70
  EXPECT_EQ(decision.tracked_close, 60);
  EXPECT_EQ(decision.untracked_close, 100);
  EXPECT_TRUE(decision.insert);
  options.close_untracked_near_clip_weight = 0.75;  // 40 + 0.75 * 60 = 85 > 70
  EXPECT_TRUE(decide_keyframe(frame, camera, input, options).insert);
  options.close_untracked_near_clip_weight = 0.5;  // 40 + 30 = 70, not more than 70
  decision = decide_keyframe(frame, camera, input, options);
  EXPECT_FALSE(decision.insert);
  EXPECT_EQ(decision.tracked_close, 60);  // near-clip tracked points (0-39) still count as tracked
  EXPECT_EQ(decision.untracked_close, 100);
  // Equally exposed pairs carry no marks (near_clip empty): the weight changes nothing.
  frame.features.near_clip.clear();
  EXPECT_TRUE(decide_keyframe(frame, camera, input, options).insert);
}

// Cameras exposed apart: in the reference-ratio rule, near-clip points count
// reference_near_clip_weight on both sides (default 1: the rule as before).
TEST(KeyframeDecision, ReferenceRatioWeighsNearClipPoints) {
  const PinholeStereo camera = test::synthetic_camera();
  const Frame frame = make_counted_frame(camera, 200, 50);  // 200 tracked close: the close rule is quiet
  KeyframeDecisionInput input;
  input.frames_since_keyframe = 3;
  input.tracked_inliers = 340;  // 100 clear + 240 near a clip edge
  input.tracked_inliers_near_clip = 240;
  input.keyframes_in_map = 5;
  input.reference_tracked_points = 480;  // 100 clear + 380 near a clip edge
  input.reference_points_near_clip = 380;
  TrackerOptions options;
  EXPECT_DOUBLE_EQ(options.reference_near_clip_weight, 1.0);
  EXPECT_TRUE(decide_keyframe(frame, camera, input, options).insert);  // 340 < 0.75 x 480 = 360
  options.reference_near_clip_weight = 0.0;  // 100 clear tracked, not < 0.75 x 100 clear in the reference
  EXPECT_FALSE(decide_keyframe(frame, camera, input, options).insert);
  options.reference_near_clip_weight = 0.5;  // 100 + 120 = 220, not < 0.75 x (100 + 190) = 217.5
  EXPECT_FALSE(decide_keyframe(frame, camera, input, options).insert);
  input.tracked_inliers = 300;  // 70 clear + 230 near clip: 70 + 115 = 185 < 217.5
  input.tracked_inliers_near_clip = 230;
  EXPECT_TRUE(decide_keyframe(frame, camera, input, options).insert);
  // No marks (equally exposed pairs): any weight leaves the rule as it was.
  input.tracked_inliers = 340;
  input.tracked_inliers_near_clip = 0;
  input.reference_points_near_clip = 0;
  options.reference_near_clip_weight = 0.0;
  EXPECT_TRUE(decide_keyframe(frame, camera, input, options).insert);
}

TEST(KeyframeDecision, NoKeyframeRightAfterRelocalizationInABigMap) {
  const PinholeStereo camera = test::synthetic_camera();
  const Frame frame = make_counted_frame(camera, 20, 300);
  KeyframeDecisionInput input;
  input.frames_since_relocalization = 2;
  input.frames_since_keyframe = 30;
  input.tracked_inliers = 60;
  input.keyframes_in_map = 40;
  input.reference_tracked_points = 300;
  EXPECT_FALSE(decide_keyframe(frame, camera, input, TrackerOptions{}).insert);
}

// A keyframe seeing three points: one observed in stereo by two keyframes (weight 4), one by two
// keyframes of which the other saw it without depth (weight 3), one in stereo by this keyframe only
// (weight 2). ORB-SLAM2's TrackedMapPoints(3) counts the first two; counting keyframes, none.
TEST(KeyframeDecision, ReferencePointsCountedByObservationWeightWithAMapper) {
  const PinholeStereo camera = test::synthetic_camera();
  const Frame stereo_frame = make_counted_frame(camera, 0, 3);
  Map map;
  Keyframe& reference = map.keyframes[1];
  reference.id = 1;
  reference.features = stereo_frame.features;
  reference.point_ids = {101, 102, 103};
  Keyframe& other = map.keyframes[2];
  other.id = 2;
  other.features = stereo_frame.features;
  other.features.depth_m[1] = -1.f;  // keypoint 1 of the other keyframe has no stereo match
  other.point_ids = {101, 102, kNoId};
  for (const PointId id : {101, 102, 103}) map.points[id].id = id;
  map.points[101].observations = {{1, 0}, {2, 0}};
  map.points[102].observations = {{1, 1}, {2, 1}};
  map.points[103].observations = {{1, 2}};
  EXPECT_EQ(count_reference_points(reference, map, 3, ObservationCount::weighted), 2);
  EXPECT_EQ(count_reference_points(reference, map, 3, ObservationCount::keyframes), 0);
  EXPECT_EQ(count_reference_points(reference, map, 2, ObservationCount::keyframes), 2);
}

// Revisits (issue 41): a keyframe made long before, near the frame's pose and looking the same way,
// covers it; recent keyframes, far ones, ones looking elsewhere and culled ones do not.
TEST(KeyframeDecision, RevisitCoveredByAnOldNearKeyframeOnly) {
  const PinholeStereo camera = test::synthetic_camera();  // baseline 0.11 m: covered within 0.33 m
  TrackerOptions options;                                 // 10 s, 3 baselines, 15 degrees
  Frame frame = make_counted_frame(camera, 60, 200);
  frame.stamp_ns = 60'000'000'000;
  frame.T_wc.translation() = Eigen::Vector3d(1.0, 2.0, 0.5);
  Map map;
  auto add = [&](KeyframeId id, double age_s, const Eigen::Vector3d& offset, double yaw_deg) {
    Keyframe& kf = map.keyframes[id];
    kf.id = id;
    kf.stamp_ns = frame.stamp_ns - static_cast<std::int64_t>(age_s * 1e9);
    kf.T_wc = frame.T_wc;
    kf.T_wc.translation() += offset;
    kf.T_wc.linear() =
        frame.T_wc.linear() * Eigen::AngleAxisd(yaw_deg * kPi / 180.0, Eigen::Vector3d::UnitY()).matrix();
    return &kf;
  };
  add(1, 5.0, Eigen::Vector3d(0.1, 0, 0), 0.0);    // too recent
  add(2, 30.0, Eigen::Vector3d(0.4, 0, 0), 0.0);   // too far (0.4 > 0.33 m)
  add(3, 30.0, Eigen::Vector3d(0.1, 0, 0), 20.0);  // looks 20 degrees away
  add(4, 30.0, Eigen::Vector3d(0, 0.2, 0), 5.0)->culled = true;
  EXPECT_FALSE(revisit_covered(frame, map, camera, options));
  add(5, 10.5, Eigen::Vector3d(0, 0.3, 0), 12.0);  // old enough, 0.3 m, 12 degrees
  EXPECT_TRUE(revisit_covered(frame, map, camera, options));
  options.revisit_min_age_s = 0.0;  // off
  EXPECT_FALSE(revisit_covered(frame, map, camera, options));
}

// Revisits looking further away (issue 41, room_laps' lap 2): an old keyframe within the distance but
// 20 degrees off covers the frame when >= 99 % of its tracked inliers are old points (their reference
// keyframe >= 10 s old), and not below that share, nor without an old keyframe near.
TEST(KeyframeDecision, RevisitCoveredByOldPointsWhenLookingFurtherAway) {
  const PinholeStereo camera = test::synthetic_camera();
  TrackerOptions options;  // 10 s, 3 baselines, 15 degrees, old share 0.99
  Frame frame = make_counted_frame(camera, 60, 200);
  frame.stamp_ns = 60'000'000'000;
  Map map;
  auto add = [&](KeyframeId id, double age_s, double x_m, double yaw_deg) {
    Keyframe& kf = map.keyframes[id];
    kf.id = id;
    kf.stamp_ns = frame.stamp_ns - static_cast<std::int64_t>(age_s * 1e9);
    kf.T_wc = frame.T_wc;
    kf.T_wc.translation().x() += x_m;
    kf.T_wc.linear() = Eigen::AngleAxisd(yaw_deg * kPi / 180.0, Eigen::Vector3d::UnitY()).matrix();
  };
  add(1, 2.0, 0.0, 0.0);    // recent (the keyframe just made): covers nothing
  add(2, 30.0, 0.1, 20.0);  // old, near, 20 degrees off
  // The frame's 60 tracked points: the first `old` made by keyframe 2, the others by keyframe 1.
  auto points_made = [&](int old) {
    for (int i = 0; i < 60; ++i) {
      const PointId id = frame.point_ids[static_cast<std::size_t>(i)];
      map.points[id].id = id;
      map.points[id].reference_kf = i < old ? 2 : 1;
    }
  };
  points_made(60);
  EXPECT_NEAR(old_inlier_share(frame, map, options.revisit_min_age_s), 1.0, 1e-12);
  EXPECT_TRUE(revisit_covered(frame, map, camera, options));
  points_made(50);  // 0.83 < 0.99
  EXPECT_NEAR(old_inlier_share(frame, map, options.revisit_min_age_s), 50.0 / 60.0, 1e-12);
  EXPECT_FALSE(revisit_covered(frame, map, camera, options));
  options.revisit_min_old_inlier_share = 0.8;
  EXPECT_TRUE(revisit_covered(frame, map, camera, options));
  frame.outlier[0] = true;  // an outlier is not an inlier: 49 / 59
  EXPECT_NEAR(old_inlier_share(frame, map, options.revisit_min_age_s), 49.0 / 59.0, 1e-12);
  frame.outlier[0] = false;
  points_made(40);  // 0.67 < 0.8
  EXPECT_FALSE(revisit_covered(frame, map, camera, options));
  points_made(60);
  options.revisit_min_old_inlier_share = 0.0;  // the angle alone
  EXPECT_FALSE(revisit_covered(frame, map, camera, options));
  options = TrackerOptions{};
  map.keyframes.at(2).T_wc.translation().x() += 0.3;  // 0.4 m away: not near
  EXPECT_FALSE(revisit_covered(frame, map, camera, options));
}

// A covered frame makes no keyframe where the close-point rule would make one, but weak tracking
// (under a quarter of the reference keyframe's points) still does.
TEST(KeyframeDecision, RevisitSuppressesAKeyframeUnlessTrackingIsWeak) {
  const PinholeStereo camera = test::synthetic_camera();
  const Frame frame = make_counted_frame(camera, 60, 200);
  KeyframeDecisionInput input;
  input.frames_since_keyframe = 3;
  input.tracked_inliers = 60;
  input.keyframes_in_map = 5;
  input.reference_tracked_points = 70;
  input.revisit_covered = true;
  KeyframeDecision decision = decide_keyframe(frame, camera, input, TrackerOptions{});
  EXPECT_FALSE(decision.insert);
  EXPECT_TRUE(decision.covered);
  input.reference_tracked_points = 300;  // 60 < 0.25 * 300: weak
  decision = decide_keyframe(frame, camera, input, TrackerOptions{});
  EXPECT_TRUE(decision.insert);
  EXPECT_FALSE(decision.covered);
}

}  // namespace
}  // namespace heslam

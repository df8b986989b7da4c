// The local mapper's messages: keyframe and point states (and the version markers) written and
// applied back to a mirror, as every map reader applies them; loop corrections decoded, bad ones refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/messages/loop_correction.hpp"
#include "components/messages/map_state.hpp"
#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::messages {
namespace {

Pose3 pose(double angle_rad, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d(0.2, -0.5, 1.0).normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

// Largest element difference of two poses (Eigen's isApprox on Isometry trips a GCC 12 false
// -Wmaybe-uninitialized with -march=native).
double pose_difference(const Pose3& a, const Pose3& b) {
  double worst = 0.0;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  return worst;
}

// A mirror map holding keyframe 7 with 4 keypoints, as the frontend has it before the mapper speaks.
Map mirror_with_keyframe(KeyframeId id) {
  Map map;
  Keyframe& kf = map.keyframes[id];
  kf.id = id;
  kf.point_ids.assign(4, kNoId);
  return map;
}

TEST(MapStateMessages, KeyframeStateRoundTripsThroughAMirror) {
  Keyframe keyframe;
  keyframe.id = 7;
  keyframe.T_wc = pose(0.3, {1.0, -2.0, 0.5});
  keyframe.parent = 3;
  keyframe.covisible = {{3, 120}, {5, 40}};
  keyframe.culled = true;
  std::vector<msg::CovisibleKeyframe> buffer;
  const msg::KeyframeState message = to_state_message(keyframe, 42, buffer);
  EXPECT_EQ(message.map_version, 42u);

  Map mirror = mirror_with_keyframe(7);
  ASSERT_TRUE(apply_keyframe_state(mirror, message));
  const Keyframe& mirrored = mirror.keyframes.at(7);
  EXPECT_LT(pose_difference(mirrored.T_wc, keyframe.T_wc), 1e-12);
  EXPECT_EQ(mirrored.parent, 3u);
  EXPECT_EQ(mirrored.covisible, keyframe.covisible);
  EXPECT_TRUE(mirrored.culled);
  EXPECT_EQ(mirror.version, 0u);  // only the version markers advance it
}

// Every mirror (the frontend's, the loop closer's, the viewer's) applies states with apply_keyframe_state:
// a culled keyframe's features and point slots go there with their memory, as in the mapper (issue 41).
TEST(MapStateMessages, ACulledKeyframesStateReleasesItsFeaturesInAMirror) {
  Map mirror = mirror_with_keyframe(7);
  Keyframe& held = mirror.keyframes.at(7);
  held.features.keypoints.resize(4);
  held.features.descriptors.resize(4);
  held.features.u_right_px.assign(4, 10.f);
  held.features.depth_m.assign(4, 2.f);
  held.point_ids = {11, kNoId, 12, 13};
  Keyframe state;
  state.id = 7;
  state.T_wc = pose(0.1, {0.5, 0.0, 0.0});
  state.parent = 3;
  state.culled = true;
  std::vector<msg::CovisibleKeyframe> buffer;
  ASSERT_TRUE(apply_keyframe_state(mirror, to_state_message(state, 9, buffer)));
  const Keyframe& mirrored = mirror.keyframes.at(7);
  EXPECT_TRUE(mirrored.culled);
  EXPECT_EQ(mirrored.parent, 3u);
  EXPECT_LT(pose_difference(mirrored.T_wc, state.T_wc), 1e-12);
  EXPECT_EQ(mirrored.features.size(), 0u);
  EXPECT_EQ(mirrored.features.keypoints.capacity(), 0u);
  EXPECT_EQ(mirrored.features.descriptors.capacity(), 0u);
  EXPECT_EQ(mirrored.features.depth_m.capacity(), 0u);
  EXPECT_EQ(mirrored.point_ids.capacity(), 0u);
}

// The markers that end every batch of states: id 0 on both topics, carrying the batch's map version;
// a mirror holds version v completely once both topics' markers reached v.
TEST(MapStateMessages, VersionMarkersEndABatchOnBothTopics) {
  const msg::KeyframeState keyframe_marker = keyframe_version_marker(12);
  const msg::MapPointState point_marker = point_version_marker(11);
  EXPECT_TRUE(is_version_marker(keyframe_marker));
  EXPECT_TRUE(is_version_marker(point_marker));
  EXPECT_EQ(keyframe_marker.map_version, 12u);
  EXPECT_EQ(keyframe_marker.correction_id, 0u);                 // a keyframe's batch
  EXPECT_EQ(keyframe_version_marker(13, 7).correction_id, 7u);  // the batch that applied correction 7
  MirrorVersion version;
  version.keyframe_states = keyframe_marker.map_version;
  EXPECT_EQ(version.complete(), 0u);  // no point marker yet
  version.point_states = point_marker.map_version;
  EXPECT_EQ(version.complete(), 11u);
}

TEST(MapStateMessages, PointStateRoundTripsAndMergeRedirectsObservations) {
  MapPoint point;
  point.id = 100;
  point.p_w = {1.5, -0.25, 4.0};
  for (std::size_t i = 0; i < point.descriptor.size(); ++i) point.descriptor[i] = static_cast<std::uint8_t>(3 * i + 1);
  point.normal = Eigen::Vector3d(0.0, 0.6, 0.8);
  point.min_distance_m = 1.25f;
  point.max_distance_m = 9.5f;
  point.reference_kf = 7;
  point.observations = {{7, 2}};
  std::vector<msg::PointObservation> buffer;
  Map mirror = mirror_with_keyframe(7);
  apply_point_state(mirror, to_state_message(point, 9, buffer));
  const MapPoint& mirrored = mirror.points.at(100);
  EXPECT_EQ(mirrored.p_w, point.p_w);
  EXPECT_EQ(mirrored.descriptor, point.descriptor);
  EXPECT_TRUE(mirrored.normal.isApprox(point.normal, 1e-7));
  EXPECT_EQ(mirrored.min_distance_m, 1.25f);
  EXPECT_EQ(mirrored.max_distance_m, 9.5f);
  EXPECT_EQ(mirrored.reference_kf, 7u);
  EXPECT_EQ(mirrored.observations, point.observations);
  EXPECT_EQ(mirror.keyframes.at(7).point_ids[2], 100u);  // the keyframe now sees the point

  // Point 100 merges into 200, which keyframe 7 already sees at keypoint 3: the mirror drops 100 and
  // empties keypoint 2, as the mapper does (a keyframe never sees one point twice).
  MapPoint into = point;
  into.id = 200;
  into.observations = {{7, 3}};
  apply_point_state(mirror, to_state_message(into, 10, buffer));
  apply_point_state(mirror, merged_state_message(100, 200, 10));
  EXPECT_EQ(mirror.points.count(100), 0u);
  EXPECT_EQ(mirror.keyframes.at(7).point_ids[2], kNoId);
  EXPECT_EQ(mirror.keyframes.at(7).point_ids[3], 200u);

  // Point 300 merges into 400, which keyframe 7 does not see yet: keypoint 1 follows the merge.
  MapPoint source = point;
  source.id = 300;
  source.observations = {{7, 1}};
  MapPoint target = point;
  target.id = 400;
  target.observations = {};
  apply_point_state(mirror, to_state_message(source, 11, buffer));
  apply_point_state(mirror, to_state_message(target, 11, buffer));
  apply_point_state(mirror, merged_state_message(300, 400, 11));
  EXPECT_EQ(mirror.keyframes.at(7).point_ids[1], 400u);
  const std::vector<std::pair<KeyframeId, int>> redirected{{7, 1}};
  EXPECT_EQ(mirror.points.at(400).observations, redirected);

  // A state that no longer names an observation empties that keypoint (a BA outlier in the mapper).
  target.observations = {};
  apply_point_state(mirror, to_state_message(target, 12, buffer));
  EXPECT_EQ(mirror.keyframes.at(7).point_ids[1], kNoId);
}

TEST(MapStateMessages, LoopCorrectionIsConvertedAndBadOnesAreRejectedWithTheirId) {
  std::vector<msg::CorrectedKeyframePose> poses(2);
  poses[0].keyframe_id = 4;
  poses[0].T_wc = to_message(pose(0.1, {1, 2, 3}));
  poses[1].keyframe_id = 9;
  poses[1].T_wc = to_message(pose(-0.2, {0, 0, 1}));
  std::vector<msg::PointMerge> merges{{11, 22}};
  msg::LoopCorrection message{};
  message.id = 5;
  message.map_version = 30;
  message.loop_keyframe_id = 9;
  message.matched_keyframe_id = 4;
  message.T_matched_loop = to_message(pose(0.05, {0.1, 0, 0}));
  runtime::borrow(message.corrected_poses, poses);
  runtime::borrow(message.point_merges, merges);
  const LoopCorrection correction = to_loop_correction(message);
  EXPECT_EQ(correction.id, 5u);
  EXPECT_EQ(correction.map_version, 30u);
  EXPECT_EQ(correction.loop_kf, 9u);
  EXPECT_EQ(correction.matched_kf, 4u);
  ASSERT_EQ(correction.corrected_T_wc.size(), 2u);
  EXPECT_EQ(correction.corrected_T_wc[1].first, 9u);
  EXPECT_LT(pose_difference(correction.corrected_T_wc[1].second, pose(-0.2, {0, 0, 1})), 1e-12);
  ASSERT_EQ(correction.point_merges.size(), 1u);
  EXPECT_EQ(correction.point_merges[0], (std::pair<PointId, PointId>(11, 22)));

  merges[0].into_id = 11;  // a point merging into itself
  try {
    to_loop_correction(message);
    FAIL() << "expected a rejection";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("loop correction 5"), std::string::npos) << error.what();
  }
}

TEST(MapStateMessages, EveryCorrectionKindTravels) {
  for (const CorrectionKind kind :
       {CorrectionKind::kLoop, CorrectionKind::kGlobalBundleAdjustment, CorrectionKind::kMerge}) {
    LoopCorrection correction;
    correction.id = 8;
    correction.loop_kf = 9;
    correction.matched_kf = 4;
    correction.kind = kind;
    const LoopCorrectionMessage message(correction);
    EXPECT_EQ(to_loop_correction(message.get()).kind, kind);
  }
}

}  // namespace
}  // namespace heslam::messages

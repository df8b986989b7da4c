// The frontend's mirror of the mapper's map: states wait for their batch to be complete and are
// applied together; a correction's batch moves our keyframes in flight with their reference
// keyframe (exactly T_new(ref) T_old(ref)^-1, their new points too) and leaves the others alone.
#include <gtest/gtest.h>

#include "components/frontend/batched_mirror.hpp"
#include "components/messages/map_state.hpp"
#include "components/messages/pose.hpp"
#include "runtime/sequence.hpp"

namespace heslam::frontend {
namespace {

Pose3 pose(double yaw_rad, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = t;
  return T;
}

msg::KeyframeState keyframe_state(KeyframeId id, std::uint64_t version, const Pose3& T_wc) {
  msg::KeyframeState state{};
  state.id = id;
  state.map_version = version;
  state.T_wc = messages::to_message(T_wc);
  return state;
}

msg::KeyframeState keyframe_marker(std::uint64_t version, std::uint64_t correction_id = 0) {
  msg::KeyframeState marker{};
  marker.id = messages::kVersionMarkerId;
  marker.map_version = version;
  marker.correction_id = correction_id;
  return marker;
}

msg::MapPointState point_marker(std::uint64_t version) {
  msg::MapPointState marker{};
  marker.id = messages::kVersionMarkerId;
  marker.map_version = version;
  return marker;
}

msg::MapPointState point_state(PointId id, std::uint64_t version, const Eigen::Vector3d& p_w, KeyframeId reference) {
  msg::MapPointState state{};
  state.id = id;
  state.map_version = version;
  for (int k = 0; k < 3; ++k) state.position_w_m[k] = p_w[k];
  state.reference_keyframe_id = reference;
  return state;
}

// Keyframes 1 (the mapper's), 2 and 3 (ours, in flight: 2 tracked against 1, 3 against 2), each
// with one point it created; keyframe 4 (ours) was tracked after the correction.
Map make_map() {
  Map map;
  for (KeyframeId id = 1; id <= 4; ++id) {
    Keyframe kf;
    kf.id = id;
    kf.T_wc = pose(0.1 * static_cast<double>(id), Eigen::Vector3d(static_cast<double>(id), 0, 0));
    kf.point_ids = {100 + id};
    map.keyframes.emplace(id, kf);
    MapPoint point;
    point.id = 100 + id;
    point.p_w = kf.T_wc * Eigen::Vector3d(0, 0, 3);
    point.reference_kf = id;
    point.observations = {{id, 0}};
    map.points.emplace(point.id, point);
  }
  return map;
}

double difference(const Pose3& a, const Pose3& b) { return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff(); }

TEST(FrontendBatchedMirror, StatesWaitUntilBothMarkersOfTheirVersionArrived) {
  Map map = make_map();
  BatchedMirror mirror;
  const Pose3 refined = pose(0.3, Eigen::Vector3d(1, 2, 3));
  mirror.add(keyframe_state(1, 5, refined));
  mirror.add(point_state(101, 5, Eigen::Vector3d(7, 8, 9), 1));
  mirror.add(keyframe_marker(5));
  BatchedMirror::Applied applied = mirror.apply(map);
  EXPECT_EQ(applied.keyframe_states, 0);  // the point marker of version 5 is missing
  EXPECT_LT(difference(map.keyframes.at(1).T_wc, pose(0.1, Eigen::Vector3d(1, 0, 0))), 1e-15);
  EXPECT_EQ(mirror.version().complete(), 0u);
  EXPECT_EQ(mirror.waiting(), 2u);

  mirror.add(point_marker(5));
  applied = mirror.apply(map);
  EXPECT_EQ(applied.keyframe_states, 1);
  EXPECT_EQ(applied.point_states, 1);
  EXPECT_FALSE(applied.correction);
  EXPECT_EQ(mirror.version().complete(), 5u);
  EXPECT_LT(difference(map.keyframes.at(1).T_wc, refined), 1e-12);
  EXPECT_EQ(map.points.at(101).p_w, Eigen::Vector3d(7, 8, 9));
  EXPECT_EQ(mirror.waiting(), 0u);
}

TEST(FrontendBatchedMirror, DisposeAfterAWaitingStateCullsThePoint) {
  Map map = make_map();
  BatchedMirror mirror;
  mirror.add(point_state(101, 3, Eigen::Vector3d(1, 1, 1), 1));
  mirror.dispose_point(101);
  mirror.dispose_point(102);  // nothing of it waits: culled at the next apply
  mirror.add(keyframe_marker(3));
  mirror.add(point_marker(3));
  mirror.apply(map);
  EXPECT_TRUE(map.points.at(101).culled);
  EXPECT_TRUE(map.points.at(102).culled);
  EXPECT_FALSE(map.points.at(103).culled);
}

TEST(FrontendBatchedMirror, MergeChainOfABatchEndsAtItsLastTarget) {
  Map map = make_map();
  BatchedMirror mirror;
  // 103 merged into 102, which then merged into 101: keyframes 2 and 3 see 101, whatever order
  // the two merges are applied in.
  msg::MapPointState first = point_state(103, 3, Eigen::Vector3d::Zero(), 3);
  first.culled = true;
  first.merged_into = 102;
  msg::MapPointState second = point_state(102, 3, Eigen::Vector3d::Zero(), 2);
  second.culled = true;
  second.merged_into = 101;
  mirror.add(first);
  mirror.add(second);
  mirror.add(keyframe_marker(3));
  mirror.add(point_marker(3));
  mirror.apply(map);
  EXPECT_EQ(map.point(102), nullptr);
  EXPECT_EQ(map.point(103), nullptr);
  EXPECT_EQ(map.keyframes.at(2).point_ids[0], 101u);
  EXPECT_EQ(map.keyframes.at(3).point_ids[0], 101u);
  EXPECT_EQ(map.points.at(101).observations.size(), 3u);
}

TEST(FrontendBatchedMirror, CorrectionBatchMovesOwnKeyframesInFlightWithTheirReference) {
  Map map = make_map();
  const Map before = map;
  BatchedMirror mirror;
  mirror.own_keyframe(2, 1, 6);  // tracked against kf 1 at version 6, before the correction (7)
  mirror.own_keyframe(3, 2, 6);  // tracked against kf 2, itself in flight
  mirror.own_keyframe(4, 1, 7);  // tracked in the corrected map
  const Pose3 corrected1 = pose(0.25, Eigen::Vector3d(1.2, -0.1, 0.3));
  mirror.add(keyframe_state(1, 7, corrected1));
  mirror.add(keyframe_marker(7, /*correction_id=*/42));
  mirror.add(point_marker(7));
  const BatchedMirror::Applied applied = mirror.apply(map);
  EXPECT_TRUE(applied.correction);
  EXPECT_EQ(applied.keyframes_moved, 2);

  const Pose3 motion = corrected1 * before.keyframes.at(1).T_wc.inverse();
  for (const KeyframeId id : {KeyframeId{2}, KeyframeId{3}}) {
    EXPECT_LT(difference(map.keyframes.at(id).T_wc, motion * before.keyframes.at(id).T_wc), 1e-12) << "keyframe " << id;
    EXPECT_LT((map.points.at(100 + id).p_w - motion * before.points.at(100 + id).p_w).norm(), 1e-12)
        << "point of " << id;
  }
  EXPECT_LT(difference(map.keyframes.at(4).T_wc, before.keyframes.at(4).T_wc), 1e-15);
  EXPECT_EQ(map.points.at(104).p_w, before.points.at(104).p_w);

  // Keyframe 2's state arrives later (the mapper moved it the same way): it is the mapper's from
  // then on, and a second correction's batch does not move it again.
  mirror.add(keyframe_state(2, 8, map.keyframes.at(2).T_wc));
  mirror.add(keyframe_state(1, 9, pose(0.0, Eigen::Vector3d::Zero())));
  mirror.add(keyframe_marker(9, 43));
  mirror.add(point_marker(9));
  const Map between = map;
  const Pose3 motion2 = pose(0.0, Eigen::Vector3d::Zero()) * between.keyframes.at(1).T_wc.inverse();
  // kf 4 (tracked at 7, before this correction, against kf 1) moves with kf 1; kf 2 has its state
  // (the mapper's from now on, not moved by us); kf 3 follows kf 2, which its state kept in place
  // (up to the rounding of the pose through the message).
  EXPECT_EQ(mirror.apply(map).keyframes_moved, 2);
  EXPECT_LT(difference(map.keyframes.at(2).T_wc, between.keyframes.at(2).T_wc), 1e-12);
  EXPECT_LT(difference(map.keyframes.at(3).T_wc, between.keyframes.at(3).T_wc), 1e-12);
  EXPECT_LT(difference(map.keyframes.at(4).T_wc, motion2 * between.keyframes.at(4).T_wc), 1e-12);
  EXPECT_GT(difference(map.keyframes.at(4).T_wc, between.keyframes.at(4).T_wc), 0.1);
}

// A restarted frontend learns its predecessor's ids from the mapper's states, also of keyframes
// its own map does not hold (states it cannot apply), so it never makes them again.
TEST(FrontendBatchedMirror, LargestCounterOfEachCreatorOverEveryIdTheStatesName) {
  BatchedMirror mirror;
  EXPECT_EQ(mirror.largest_keyframe_counter(kFrontendTag), 0u);
  mirror.add(keyframe_state(make_id(kFrontendTag, 41), 1, Pose3::Identity()));
  msg::MapPointState point = point_state(make_id(kMapperTag, 7), 1, Eigen::Vector3d::Zero(), make_id(kFrontendTag, 41));
  const std::vector<msg::PointObservation> observations{{make_id(kFrontendTag, 57), 3}};
  runtime::borrow(point.observations, observations);
  mirror.add(point);
  mirror.add(point_state(make_id(kFrontendTag, 50), 1, Eigen::Vector3d::Zero(), make_id(kFrontendTag, 41)));
  EXPECT_EQ(mirror.largest_keyframe_counter(kFrontendTag), 57u);
  EXPECT_EQ(mirror.largest_point_counter(kFrontendTag), 50u);
  EXPECT_EQ(mirror.largest_point_counter(kMapperTag), 7u);
  EXPECT_EQ(mirror.largest_keyframe_counter(kMapperTag), 0u);
}

}  // namespace
}  // namespace heslam::frontend

// Loop-correction application on a chain of keyframes: exact propagation rule.
#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <vector>

#include "components/core/mapping/correction_application.hpp"
#include "components/core/mapping/point_statistics.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

Pose3 make_pose(double yaw_rad, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = t;
  return T;
}

void expect_pose_eq(const Pose3& a, const Pose3& b, const std::string& what) {
  EXPECT_LT(test::max_abs_difference(a, b), 1e-12) << what;
}

struct Chain {
  test::SyntheticWorld world = test::make_room(800, 41);
  test::TruthMap truth;
  std::map<KeyframeId, std::uint64_t> created_version;
};

// Keyframes 1..6 in a spanning-tree chain (parent of k is k-1), kf k inserted at map version k.
Chain make_chain() {
  Chain chain;
  test::ViewOptions options;
  options.clutter = 0;
  chain.truth = test::make_truth_map(chain.world, 6, options);
  for (auto& [id, kf] : chain.truth.map.keyframes) {
    kf.parent = id == 1 ? kNoId : id - 1;
    chain.created_version[id] = id;
  }
  chain.truth.map.version = 6;
  return chain;
}

TEST(CorrectionApplication, ListedPosesSetLaterKeyframesFollowTheTree) {
  Chain chain = make_chain();
  Map& map = chain.truth.map;
  std::map<KeyframeId, Pose3> old_T_wc;
  for (const auto& [id, kf] : map.keyframes) old_T_wc[id] = kf.T_wc;
  std::map<PointId, Eigen::Vector3d> old_p_w;
  for (const auto& [id, point] : map.points) old_p_w[id] = point.p_w;

  LoopCorrection correction;
  correction.map_version = 3;  // the loop closer saw keyframes 1..3
  const Pose3 new2 = make_pose(0.05, Eigen::Vector3d(0.2, 0.0, -0.1)) * old_T_wc[2];
  const Pose3 new3 = make_pose(0.08, Eigen::Vector3d(0.3, 0.05, -0.2)) * old_T_wc[3];
  correction.corrected_T_wc = {{2, new2}, {3, new3}};

  MapChanges changes;
  EXPECT_EQ(apply_loop_correction(map, correction, chain.created_version, changes), 0);

  expect_pose_eq(map.keyframes.at(1).T_wc, old_T_wc[1], "kf 1 not listed, created before: unchanged");
  expect_pose_eq(map.keyframes.at(2).T_wc, new2, "kf 2 listed");
  expect_pose_eq(map.keyframes.at(3).T_wc, new3, "kf 3 listed");
  std::map<KeyframeId, Pose3> expected{{1, old_T_wc[1]}, {2, new2}, {3, new3}};
  for (KeyframeId k = 4; k <= 6; ++k) {
    expected[k] = expected[k - 1] * old_T_wc[k - 1].inverse() * old_T_wc[k];
    expect_pose_eq(map.keyframes.at(k).T_wc, expected[k], "kf " + std::to_string(k) + " propagated");
  }
  // The chain after kf 3 moves rigidly with kf 3.
  expect_pose_eq(map.keyframes.at(6).T_wc, new3 * old_T_wc[3].inverse() * old_T_wc[6], "rigid chain");

  int moved = 0;
  for (const auto& [id, point] : map.points) {
    const KeyframeId ref = point.reference_kf;
    const Eigen::Vector3d want = expected[ref] * (old_T_wc[ref].inverse() * old_p_w[id]);
    EXPECT_LT((point.p_w - want).norm(), 1e-12) << "point " << id << " ref " << ref;
    if (ref != 1) {
      ++moved;
      EXPECT_EQ(changes.changed_points.count(id), 1u);
    }
  }
  EXPECT_GT(moved, 0);
  EXPECT_EQ(changes.changed_keyframes, (std::set<KeyframeId>{2, 3, 4, 5, 6}));
}

TEST(CorrectionApplication, KeyframesCreatedBeforeTheVersionAndNotListedStay) {
  Chain chain = make_chain();
  Map& map = chain.truth.map;
  const Pose3 old4 = map.keyframes.at(4).T_wc;
  const Pose3 old5 = map.keyframes.at(5).T_wc;
  LoopCorrection correction;
  correction.map_version = 4;  // kf 4 was known to the loop closer and deliberately not corrected
  correction.corrected_T_wc = {{3, make_pose(0.1, Eigen::Vector3d(1, 0, 0)) * map.keyframes.at(3).T_wc}};
  MapChanges changes;
  apply_loop_correction(map, correction, chain.created_version, changes);
  expect_pose_eq(map.keyframes.at(4).T_wc, old4, "kf 4 known at version 4");
  expect_pose_eq(map.keyframes.at(5).T_wc, old5, "kf 5 follows its unchanged parent");
}

TEST(CorrectionApplication, PointMergesMoveObservations) {
  Chain chain = make_chain();
  Map& map = chain.truth.map;
  // Two points with disjoint observers.
  PointId from = kNoId;
  PointId into = kNoId;
  for (const auto& [id, point] : map.points) {
    if (from == kNoId && point.observations.front().first == 1 && point.observations.size() == 2) from = id;
    if (into == kNoId && point.observations.front().first == 5) into = id;
  }
  ASSERT_NE(from, kNoId);
  ASSERT_NE(into, kNoId);
  const auto from_observations = map.points.at(from).observations;
  LoopCorrection correction;
  correction.map_version = 6;
  correction.point_merges = {{from, into}, {12345, into}};
  MapChanges changes;
  EXPECT_EQ(apply_loop_correction(map, correction, chain.created_version, changes), 1);  // unknown 12345
  EXPECT_EQ(map.point(from), nullptr);
  EXPECT_EQ(changes.removed_points.at(from), into);
  for (const auto& [kf_id, index] : from_observations) {
    EXPECT_EQ(map.keyframes.at(kf_id).point_ids[static_cast<std::size_t>(index)], into);
    EXPECT_GE(observation_index(map.points.at(into), kf_id), 0);
  }
}

TEST(CorrectionApplication, UnknownKeyframesAreSkippedAndCounted) {
  Chain chain = make_chain();
  LoopCorrection correction;
  correction.map_version = 6;
  correction.corrected_T_wc = {{99, Pose3::Identity()}};
  MapChanges changes;
  EXPECT_EQ(apply_loop_correction(chain.truth.map, correction, chain.created_version, changes), 1);
  EXPECT_TRUE(changes.changed_keyframes.empty());
}

// The application updates a point's statistics through a keyframe hash table and moves points with a
// per-keyframe transform computed once: bit for bit what a point-by-point update on the map gives.
TEST(CorrectionApplication, MovedPointsAndStatisticsMatchAPointByPointUpdate) {
  Chain chain = make_chain();
  Map& map = chain.truth.map;
  const Map before = map;
  LoopCorrection correction;
  correction.map_version = 6;
  for (const auto& [id, kf] : map.keyframes) {
    if (id == 1) continue;  // one keyframe stays: its points do not move
    const double k = static_cast<double>(id);
    correction.corrected_T_wc.emplace_back(id, make_pose(0.01 * k, Eigen::Vector3d(0.02 * k, -0.01, 0.03)) * kf.T_wc);
  }
  const PointId into = map.points.begin()->first;
  const PointId from = std::next(map.points.begin(), 5)->first;
  correction.point_merges = {{from, into}};
  MapChanges changes;
  ASSERT_EQ(apply_loop_correction(map, correction, chain.created_version, changes), 0);

  Map expected = before;
  std::map<KeyframeId, Pose3> new_T_wc;
  for (const auto& [id, T_wc] : correction.corrected_T_wc) new_T_wc[id] = T_wc;
  for (auto& [id, point] : expected.points) {
    const auto moved = new_T_wc.find(point.reference_kf);
    if (moved == new_T_wc.end()) continue;
    point.p_w = moved->second * (before.keyframes.at(point.reference_kf).T_wc.inverse() * point.p_w);
  }
  for (const auto& [id, T_wc] : new_T_wc) expected.keyframes.at(id).T_wc = T_wc;
  replace_point(expected, from, into);
  for (const PointId id : changes.changed_points) update_point_statistics(expected, id);

  ASSERT_EQ(map.points.size(), expected.points.size());
  int moved = 0;
  for (const auto& [id, point] : map.points) {
    const MapPoint& want = expected.points.at(id);
    EXPECT_EQ(point.p_w, want.p_w) << "point " << id;
    EXPECT_EQ(point.normal, want.normal) << "point " << id;
    EXPECT_EQ(point.min_distance_m, want.min_distance_m) << "point " << id;
    EXPECT_EQ(point.max_distance_m, want.max_distance_m) << "point " << id;
    EXPECT_EQ(point.descriptor, want.descriptor) << "point " << id;
    EXPECT_EQ(point.reference_kf, want.reference_kf) << "point " << id;
    if (point.p_w != before.points.at(id).p_w) ++moved;
  }
  EXPECT_GT(moved, 0);
  EXPECT_LT(moved, static_cast<int>(map.points.size()));  // keyframe 1's points stay
}

TEST(CorrectionApplication, RepresentativeDescriptorIsTheLeastMedianDistanceOne) {
  Chain chain = make_chain();
  for (const auto& [id, point] : chain.truth.map.points) {
    if (point.observations.size() < 3) continue;
    std::vector<Descriptor> descriptors;
    for (const auto& [kf_id, index] : point.observations) {
      descriptors.push_back(chain.truth.map.keyframes.at(kf_id).features.descriptors[static_cast<std::size_t>(index)]);
    }
    std::size_t best = 0;
    int best_median = 1 << 30;
    for (std::size_t i = 0; i < descriptors.size(); ++i) {
      std::vector<int> distances;
      for (const Descriptor& other : descriptors) distances.push_back(hamming_distance(descriptors[i], other));
      std::sort(distances.begin(), distances.end());
      if (distances[(distances.size() - 1) / 2] < best_median) {
        best_median = distances[(distances.size() - 1) / 2];
        best = i;
      }
    }
    EXPECT_EQ(representative_descriptor(chain.truth.map, point), descriptors[best]) << "point " << id;
  }
}

}  // namespace
}  // namespace heslam

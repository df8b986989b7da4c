// The loop correction on a drifted synthetic loop: poses back near the truth, duplicates merged.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "components/core/loop/loop_correction_builder.hpp"
#include "components/core/mapping/correction_application.hpp"
#include "tests/loop/loop_world.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

constexpr int kLoopIndex = 39;  // revisits keyframe 3's place
constexpr int kMatchedIndex = 3;

double max_position_error_m(const test::LoopWorld& w, const std::vector<std::pair<KeyframeId, Pose3>>& T_wc) {
  double largest = 0.0;
  for (const auto& [id, pose] : T_wc) {
    largest = std::max(largest, (pose.translation() - w.true_T_wc.at(id).translation()).norm());
  }
  return largest;
}

double mean_point_error_m(const test::LoopWorld& w, const Map& map) {
  double sum = 0.0;
  int count = 0;
  for (const auto& [id, point] : map.points) {
    sum += (point.p_w - w.world.points_w[static_cast<std::size_t>(w.truth_of_point.at(id))]).norm();
    ++count;
  }
  return sum / count;
}

LoopCandidate verified_loop(const test::LoopWorld& w) {
  LoopCandidate loop;
  loop.loop_kf = test::loop_kf_id(kLoopIndex);
  loop.matched_kf = test::loop_kf_id(kMatchedIndex);
  const auto ransac =
      Se3Ransac().compute(w.world.camera, test::correspondences_between(w, loop.matched_kf, loop.loop_kf));
  EXPECT_TRUE(ransac.has_value());
  if (ransac) loop.T_matched_loop = ransac->T_ab;
  return loop;
}

TEST(LoopCorrectionBuilder, DriftedLoopComesBackWithinCentimetresAndDuplicatesMerge) {
  const test::LoopWorld w = test::make_loop_world();
  std::vector<std::pair<KeyframeId, Pose3>> drifted;
  for (const auto& [id, kf] : w.map.keyframes) drifted.emplace_back(id, kf.T_wc);
  const double drift_m = max_position_error_m(w, drifted);
  ASSERT_GT(drift_m, 0.25);

  const LoopCorrectionOutput output = LoopCorrectionBuilder().compute(w.map, w.world.camera, verified_loop(w), {});
  ASSERT_TRUE(output.error.empty()) << output.error;
  const LoopCorrection& correction = output.correction;
  EXPECT_EQ(correction.map_version, w.map.version);
  EXPECT_EQ(correction.loop_kf, test::loop_kf_id(kLoopIndex));
  ASSERT_EQ(correction.corrected_T_wc.size(), w.map.keyframes.size());
  const double corrected_m = max_position_error_m(w, correction.corrected_T_wc);
  EXPECT_LT(corrected_m, 0.05) << "drift before: " << drift_m << " m";
  EXPECT_LT(corrected_m, 0.2 * drift_m);

  // Merges: loop-side duplicates into the matched side's points of the same world point.
  ASSERT_GT(correction.point_merges.size(), 100u);
  int wrong = 0;
  for (const auto& [from, into] : correction.point_merges) {
    if (w.truth_of_point.at(from) != w.truth_of_point.at(into)) ++wrong;
    EXPECT_GT(from, into) << "the loop side (newer) point is the one replaced";
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(output.stats.point_merges, static_cast<int>(correction.point_merges.size()));
  EXPECT_GE(output.stats.loop_connections, 2);
  EXPECT_GT(output.stats.graph_edges.new_loop_edges, 0);
  EXPECT_EQ(output.stats.graph_edges.spanning_tree_edges, static_cast<int>(w.map.keyframes.size()) - 1);
  EXPECT_EQ(output.stats.pose_graph.fixed_vertices, 1);

  // The mapper's side: applied to the map, the points follow their keyframes back near the truth.
  Map corrected = w.map;
  MapChanges changes;
  EXPECT_EQ(apply_loop_correction(corrected, correction, {}, changes), 0);
  EXPECT_LT(mean_point_error_m(w, corrected), 0.25 * mean_point_error_m(w, w.map));
  EXPECT_EQ(corrected.points.size(), w.map.points.size() - correction.point_merges.size());
}

TEST(LoopCorrectionBuilder, MatchedKeyframeStaysPutAndRunsRepeat) {
  const test::LoopWorld w = test::make_loop_world();
  const LoopCandidate loop = verified_loop(w);
  const LoopCorrectionOutput first = LoopCorrectionBuilder().compute(w.map, w.world.camera, loop, {});
  const LoopCorrectionOutput second = LoopCorrectionBuilder().compute(w.map, w.world.camera, loop, {});
  ASSERT_EQ(first.correction.corrected_T_wc.size(), second.correction.corrected_T_wc.size());
  for (std::size_t i = 0; i < first.correction.corrected_T_wc.size(); ++i) {
    const auto& [id, T_wc] = first.correction.corrected_T_wc[i];
    EXPECT_EQ(T_wc.matrix(), second.correction.corrected_T_wc[i].second.matrix());
    if (id == loop.matched_kf) {
      EXPECT_EQ(T_wc.matrix(), w.map.keyframes.at(id).T_wc.matrix());
    }
  }
  EXPECT_EQ(first.correction.point_merges, second.correction.point_merges);
}

TEST(LoopCorrectionBuilder, FixedLoopGroupKeepsTheVerifiedTransformExactly) {
  const test::LoopWorld w = test::make_loop_world();
  const LoopCandidate loop = verified_loop(w);
  LoopCorrectionBuilderOptions options;
  options.fix_loop_group = true;
  const LoopCorrectionOutput output = LoopCorrectionBuilder(options).compute(w.map, w.world.camera, loop, {});
  ASSERT_TRUE(output.error.empty());
  EXPECT_EQ(output.stats.pose_graph.fixed_vertices, output.stats.loop_group_keyframes + 1);
  const Pose3 expected = w.map.keyframes.at(loop.matched_kf).T_wc * loop.T_matched_loop;
  const auto loop_pose = std::find_if(output.correction.corrected_T_wc.begin(), output.correction.corrected_T_wc.end(),
                                      [&](const auto& entry) { return entry.first == loop.loop_kf; });
  ASSERT_NE(loop_pose, output.correction.corrected_T_wc.end());
  EXPECT_LT(test::max_abs_difference(loop_pose->second, expected), 1e-12);
}

// Largest change of gravity's direction in a keyframe (its roll and pitch) from the map to the correction.
double largest_gravity_change(const test::LoopWorld& w, const LoopCorrection& correction,
                              const Eigen::Vector3d& gravity_w) {
  double largest = 0.0;
  for (const auto& [id, T_wc] : correction.corrected_T_wc) {
    const Eigen::Matrix3d& R_before = w.map.keyframes.at(id).T_wc.rotation();
    largest = std::max(largest, (T_wc.rotation().transpose() * gravity_w - R_before.transpose() * gravity_w).norm());
  }
  return largest;
}

TEST(LoopCorrectionBuilder, FourDofCorrectionKeepsEveryKeyframesRollAndPitch) {
  // The loop world turns about its y axis (the cameras' y, down): gravity along +y. Its odometry drifts
  // in yaw and translation, so the 4-DoF graph can correct it as well as the 6-DoF one, without
  // touching the roll and pitch the IMU would have fixed (the verified transform's own small roll and
  // pitch errors included).
  const test::LoopWorld w = test::make_loop_world();
  const LoopCandidate loop = verified_loop(w);
  const Eigen::Vector3d gravity_w = Eigen::Vector3d::UnitY();
  LoopCorrectionBuilderOptions options;
  options.pose_graph.four_dof = true;
  options.pose_graph.gravity_w = 9.81 * gravity_w;
  const LoopCorrectionOutput four = LoopCorrectionBuilder(options).compute(w.map, w.world.camera, loop, {});
  const LoopCorrectionOutput six = LoopCorrectionBuilder().compute(w.map, w.world.camera, loop, {});
  ASSERT_TRUE(four.error.empty()) << four.error;
  ASSERT_EQ(four.correction.corrected_T_wc.size(), w.map.keyframes.size());
  const double four_m = max_position_error_m(w, four.correction.corrected_T_wc);
  const double six_m = max_position_error_m(w, six.correction.corrected_T_wc);
  const double four_gravity = largest_gravity_change(w, four.correction, gravity_w);
  const double six_gravity = largest_gravity_change(w, six.correction, gravity_w);
  std::printf("4-DoF: %.4f m from the truth, gravity in the keyframes moved %.3g; 6-DoF: %.4f m, %.3g\n", four_m,
              four_gravity, six_m, six_gravity);
  EXPECT_LT(four_m, 0.05);
  EXPECT_LT(four_gravity, 1e-12);
  EXPECT_GT(six_gravity, 1e-6);
  EXPECT_GT(four.correction.point_merges.size(), 100u);
}

TEST(LoopCorrectionBuilder, GivenPointMatchesAreMergedFirst) {
  const test::LoopWorld w = test::make_loop_world();
  LoopCandidate loop = verified_loop(w);
  // A loop-side point of the loop keyframe and the matched side's point of the same world point.
  std::map<int, PointId> matched_side;
  for (const PointId id : w.map.keyframes.at(loop.matched_kf).point_ids) {
    if (id != kNoId) matched_side[w.truth_of_point.at(id)] = id;
  }
  for (const PointId id : w.map.keyframes.at(loop.loop_kf).point_ids) {
    const auto it = id == kNoId ? matched_side.end() : matched_side.find(w.truth_of_point.at(id));
    if (it != matched_side.end() && it->second != id) {
      loop.matched_points.emplace_back(id, it->second);
      break;
    }
  }
  ASSERT_EQ(loop.matched_points.size(), 1u);
  const LoopCorrectionOutput output = LoopCorrectionBuilder().compute(w.map, w.world.camera, loop, {});
  ASSERT_FALSE(output.correction.point_merges.empty());
  EXPECT_EQ(output.correction.point_merges.front(), loop.matched_points.front());
}

TEST(LoopCorrectionBuilder, RejectsUnknownKeyframes) {
  const test::LoopWorld w = test::make_loop_world();
  LoopCandidate loop;
  loop.loop_kf = 999;
  loop.matched_kf = test::loop_kf_id(0);
  const LoopCorrectionOutput output = LoopCorrectionBuilder().compute(w.map, w.world.camera, loop, {});
  EXPECT_FALSE(output.error.empty());
  EXPECT_TRUE(output.correction.corrected_T_wc.empty());
}

}  // namespace
}  // namespace heslam

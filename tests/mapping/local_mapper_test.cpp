// The whole per-keyframe pipeline on a synthetic sequence: the map stays consistent and the mapper
// improves the frontend's keyframe poses against the ground truth.
#include <gtest/gtest.h>

#include <algorithm>

#include "components/core/mapping/local_mapper.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

void expect_consistent(const Map& map) {
  for (const auto& [id, point] : map.points) {
    ASSERT_FALSE(point.observations.empty()) << "point " << id;
    for (const auto& [kf_id, index] : point.observations) {
      const Keyframe& kf = map.keyframes.at(kf_id);
      ASSERT_FALSE(kf.culled) << "point " << id << " observed by culled keyframe " << kf_id;
      ASSERT_EQ(kf.point_ids.at(static_cast<std::size_t>(index)), id);
    }
    ASSERT_GE(observation_index(point, point.reference_kf), 0) << "point " << id;
  }
  for (const auto& [id, kf] : map.keyframes) {
    for (std::size_t i = 0; i < kf.point_ids.size(); ++i) {
      if (kf.point_ids[i] == kNoId) continue;
      const MapPoint* point = map.point(kf.point_ids[i]);
      ASSERT_NE(point, nullptr) << "keyframe " << id << " keypoint " << i;
      ASSERT_EQ(observation_index(*point, id), static_cast<int>(i));
    }
    for (const auto& [other, weight] : kf.covisible) {
      const auto& back = map.keyframes.at(other).covisible;
      ASSERT_TRUE(
          std::any_of(back.begin(), back.end(), [&](const auto& e) { return e.first == id && e.second == weight; }))
          << "edge " << id << "-" << other << " not symmetric";
    }
    if (!kf.culled && id != map.keyframes.begin()->first) {
      ASSERT_NE(kf.parent, kNoId) << "keyframe " << id;
      ASSERT_FALSE(map.keyframes.at(kf.parent).culled) << "keyframe " << id;
    }
  }
}

struct SequenceResult {
  double frontend_error_m = 0.0;  // mean keyframe position error of the poses handed to the mapper
  double mapper_error_m = 0.0;    // ... after mapping
  double median_point_error_m = 0.0;
  int keyframes = 0;
  int culled = 0;
  int triangulated = 0;
};

SequenceResult run_sequence(LocalMapper& mapper, const test::SyntheticWorld& world, int count) {
  test::FrontendEmulator frontend(world);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::map<KeyframeId, Pose3> truth;
  SequenceResult result;
  for (int k = 0; k < count; ++k) {
    const KeyframeId id = static_cast<KeyframeId>(k + 1);
    const Pose3 T_wc = test::circle_pose(k, 0.08);
    truth[id] = T_wc;
    auto view = test::make_view(world, id, T_wc, 500 + static_cast<unsigned>(k));
    Pose3 estimate = T_wc;
    if (k > 0) {  // frontend jitter: 2 cm, 0.3 deg
      estimate.translation() += 0.02 * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      const Eigen::Vector3d dr = 0.005 * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      estimate.linear() = Eigen::AngleAxisd(dr.norm(), dr.normalized()).toRotationMatrix() * estimate.linear();
    }
    result.frontend_error_m += (estimate.translation() - T_wc.translation()).norm();
    auto [kf, points] = frontend.keyframe(mapper.map(), view, estimate);
    const MapChanges changes = mapper.process_keyframe(std::move(kf), std::move(points));
    result.triangulated += changes.counts.triangulated_points;
    result.culled += changes.counts.culled_keyframes;
  }
  int live = 0;
  for (const auto& [id, kf] : mapper.map().keyframes) {
    if (kf.culled) continue;
    result.mapper_error_m += (kf.T_wc.translation() - truth.at(id).translation()).norm();
    ++live;
  }
  result.frontend_error_m /= count;
  result.mapper_error_m /= live;
  result.keyframes = live;
  std::vector<double> point_errors;
  for (const auto& [id, point] : mapper.map().points) {
    const int t = frontend.truth_of_point(point);
    if (t >= 0) point_errors.push_back((point.p_w - world.points_w[static_cast<std::size_t>(t)]).norm());
  }
  std::nth_element(point_errors.begin(), point_errors.begin() + static_cast<std::ptrdiff_t>(point_errors.size() / 2),
                   point_errors.end());
  result.median_point_error_m = point_errors[point_errors.size() / 2];
  return result;
}

TEST(LocalMapper, ImprovesFrontendPosesAndKeepsTheMapConsistent) {
  const auto world = test::make_room(2500, 91);
  LocalMapper mapper(world.camera, LocalMapperOptions{});
  const SequenceResult result = run_sequence(mapper, world, 16);
  expect_consistent(mapper.map());
  EXPECT_LT(result.mapper_error_m, 0.3 * result.frontend_error_m)
      << "frontend " << result.frontend_error_m << " m, mapper " << result.mapper_error_m << " m";
  // One stereo measurement at 3-4 m has ~4 % depth noise (10-15 cm); the mapped points are far better.
  EXPECT_LT(result.median_point_error_m, 0.05);
  EXPECT_EQ(mapper.map().version, 16u);
  EXPECT_EQ(mapper.state().keyframes_processed, 16u);
}

TEST(LocalMapper, RejectsMalformedKeyframesWithAClearError) {
  const auto world = test::make_room(300, 92);
  LocalMapper mapper(world.camera, LocalMapperOptions{});
  auto view = test::make_view(world, 1, test::circle_pose(0), 1);
  Keyframe bad = view.kf;
  bad.point_ids.pop_back();
  try {
    mapper.process_keyframe(bad, {});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("keyframe 1"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(mapper.map().keyframes.empty());
  EXPECT_EQ(mapper.state().keyframes_processed, 0u);
  mapper.process_keyframe(view.kf, {});
  EXPECT_THROW(mapper.process_keyframe(view.kf, {}), std::invalid_argument);  // duplicate id
}

TEST(LocalMapper, ObservationsOfMergedPointsFollowTheMerge) {
  const auto world = test::make_room(800, 93);
  LocalMapperOptions options;
  options.enable_triangulation = false;
  options.enable_fusion = false;
  options.enable_bundle_adjustment = false;
  options.enable_keyframe_culling = false;
  LocalMapper mapper(world.camera, options);
  test::FrontendEmulator frontend(world);
  auto view1 = test::make_view(world, 1, test::circle_pose(0), 1);
  auto [kf1, points1] = frontend.keyframe(mapper.map(), view1, view1.kf.T_wc);
  mapper.process_keyframe(kf1, points1);
  auto view2 = test::make_view(world, 2, test::circle_pose(0), 2);
  auto [kf2, points2] = frontend.keyframe(mapper.map(), view2, view2.kf.T_wc);
  mapper.process_keyframe(kf2, points2);

  const PointId from = points1[0].id;
  const PointId into = points1[1].id;
  // kf 1 and 2 both see `from` and `into`: after the merge, `into` keeps its own observations.
  LoopCorrection correction;
  correction.map_version = mapper.map().version;
  correction.point_merges = {{from, into}};
  const MapChanges changes = mapper.apply_correction(correction);
  EXPECT_EQ(changes.removed_points.at(from), into);
  EXPECT_EQ(mapper.state().merged_into.at(from), into);

  // A late keyframe from the frontend still referencing `from` observes `into` instead.
  auto view3 = test::make_view(world, 3, test::circle_pose(0), 3);
  Keyframe kf3 = view3.kf;
  std::size_t free_index = 0;
  while (view3.truth[free_index] < 0) ++free_index;
  kf3.point_ids[free_index] = from;
  mapper.process_keyframe(kf3, {});
  EXPECT_EQ(mapper.map().keyframes.at(3).point_ids[free_index], into);
}

}  // namespace
}  // namespace heslam

namespace heslam {
namespace {

TEST(MapChanges, MergeUnitesAndDropsLaterRemovals) {
  MapChanges first;
  first.map_version = 3;
  first.changed_points = {1, 2};
  first.changed_keyframes = {10};
  first.counts.triangulated_points = 4;
  MapChanges second;
  second.map_version = 4;
  second.changed_points = {3};
  second.removed_points = {{2, 3}};
  second.changed_keyframes = {11};
  second.counts.triangulated_points = 1;
  first.merge(second);
  EXPECT_EQ(first.map_version, 4u);
  EXPECT_EQ(first.changed_points, (std::set<PointId>{1, 3}));
  EXPECT_EQ(first.removed_points.at(2), 3u);
  EXPECT_EQ(first.changed_keyframes, (std::set<KeyframeId>{10, 11}));
  EXPECT_EQ(first.counts.triangulated_points, 5);
}

}  // namespace
}  // namespace heslam

namespace heslam {
namespace {

// A correction that moves every live keyframe by the same rigid transform moves the whole map
// rigidly: culled keyframes ride on their parents, points on their reference keyframes.
TEST(LocalMapper, RigidCorrectionMovesCulledKeyframesAndPointsRigidly) {
  const auto world = test::make_room(2500, 94);
  LocalMapper mapper(world.camera, LocalMapperOptions{});
  test::FrontendEmulator frontend(world);
  for (int k = 0; k < 14; ++k) {
    auto view = test::make_view(world, static_cast<KeyframeId>(k + 1), test::circle_pose(k, 0.05),
                                900 + static_cast<unsigned>(k));
    auto [kf, points] = frontend.keyframe(mapper.map(), view, view.kf.T_wc);
    mapper.process_keyframe(std::move(kf), std::move(points));
  }
  ASSERT_FALSE(mapper.state().culled_T_pc.empty()) << "the sequence should cull keyframes";
  const Map before = mapper.map();
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.3, 1.0, 0.1).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.5, -0.2, 1.0);
  LoopCorrection correction;
  correction.map_version = before.version;
  for (const auto& [id, kf] : before.keyframes) {
    if (!kf.culled) correction.corrected_T_wc.emplace_back(id, T * kf.T_wc);
  }
  const MapChanges changes = mapper.apply_correction(correction);
  EXPECT_EQ(changes.changed_keyframes.size(), before.keyframes.size());
  for (const auto& [id, kf] : mapper.map().keyframes) {
    EXPECT_LT(test::max_abs_difference(kf.T_wc, T * before.keyframes.at(id).T_wc), 1e-9)
        << "keyframe " << id << (kf.culled ? " (culled)" : "");
  }
  for (const auto& [id, point] : mapper.map().points) {
    EXPECT_LT((point.p_w - T * before.points.at(id).p_w).norm(), 1e-9) << "point " << id;
  }
  EXPECT_EQ(mapper.map().version, before.version + 1);
}

}  // namespace
}  // namespace heslam

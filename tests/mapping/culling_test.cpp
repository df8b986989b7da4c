// Keyframe culling, recent point culling and spanning-tree repair on known configurations.
#include <gtest/gtest.h>

#include "components/core/mapping/keyframe_culling.hpp"
#include "components/core/mapping/local_mapper.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

test::ViewOptions exact_level0() {
  test::ViewOptions options;
  options.max_octave = 0;
  options.clutter = 0;
  return options;
}

TEST(KeyframeCulling, KeyframeSeenByManyOthersIsRedundant) {
  const auto world = test::make_room(800, 51);
  // 8 keyframes 0.1 deg apart: every point is seen by all of them.
  auto truth = test::make_truth_map(world, 8, exact_level0(), 0.001);
  EXPECT_TRUE(is_redundant_keyframe(truth.map, 4, world.camera, KeyframeCullingOptions{}));
}

TEST(KeyframeCulling, KeyframeWithOwnPointsIsKept) {
  const auto world = test::make_room(800, 51);
  // 0.6 rad apart: neighbours share only part of the view, and no point has three other observers.
  auto truth = test::make_truth_map(world, 4, exact_level0(), 0.6);
  for (KeyframeId id = 1; id <= 4; ++id) {
    EXPECT_FALSE(is_redundant_keyframe(truth.map, id, world.camera, KeyframeCullingOptions{})) << id;
  }
}

TEST(KeyframeCulling, CullsSequentiallyUntilPointsNeedTheRest) {
  const auto world = test::make_room(800, 51);
  auto truth = test::make_truth_map(world, 8, exact_level0(), 0.001);
  for (auto& [id, kf] : truth.map.keyframes) kf.parent = id == 1 ? kNoId : id - 1;
  MapChanges changes;
  const auto culled = cull_redundant_neighbours(truth.map, 8, world.camera, KeyframeCullingOptions{}, changes);
  // Points start with 8 observers; a keyframe is culled while its points keep > 3 observers and
  // >= 3 others: five of 2..7 go, the sixth is needed (3 observers left: 1, it, 8), and 1 (the
  // origin) and 8 (the current keyframe) are never candidates.
  EXPECT_EQ(culled.size(), 5u);
  EXPECT_EQ(std::count(culled.begin(), culled.end(), 1u), 0);
  EXPECT_EQ(std::count(culled.begin(), culled.end(), 8u), 0);
  for (const KeyframeId id : culled) {
    const Keyframe& kf = truth.map.keyframes.at(id);
    EXPECT_TRUE(kf.culled);
    EXPECT_TRUE(kf.covisible.empty());
    // Its features are released (issue 41): only the pose and parent of a culled keyframe are used.
    EXPECT_EQ(kf.point_ids.capacity(), 0u);  // the memory, not only the size
    EXPECT_EQ(kf.features.descriptors.capacity(), 0u);
    EXPECT_EQ(kf.features.size(), 0u);
    EXPECT_TRUE(kf.features.descriptors.empty() && kf.features.depth_m.empty() && kf.features.u_right_px.empty());
    EXPECT_EQ(kf.features.pyramid.levels, truth.map.keyframes.at(8).features.pyramid.levels);
  }
  // Survivors' parents are live keyframes.
  for (KeyframeId id = 2; id <= 8; ++id) {
    if (truth.map.keyframes.at(id).culled) continue;
    const KeyframeId parent = truth.map.keyframes.at(id).parent;
    EXPECT_FALSE(truth.map.keyframes.at(parent).culled) << id;
  }
  for (const auto& [id, point] : truth.map.points) {
    for (const auto& [kf_id, index] : point.observations) EXPECT_FALSE(truth.map.keyframes.at(kf_id).culled);
  }
}

TEST(KeyframeCulling, ChildrenAreReattachedByCovisibility) {
  Map map;
  for (KeyframeId id = 1; id <= 4; ++id) map.keyframes[id].id = id;
  map.keyframes[2].parent = 1;
  map.keyframes[3].parent = 2;
  map.keyframes[4].parent = 2;
  map.keyframes[1].covisible = {{2, 50}, {3, 20}};
  map.keyframes[2].covisible = {{1, 50}, {3, 40}, {4, 30}};
  map.keyframes[3].covisible = {{2, 40}, {4, 25}, {1, 20}};
  map.keyframes[4].covisible = {{2, 30}, {3, 25}};
  MapChanges changes;
  cull_keyframe(map, 2, changes);
  EXPECT_EQ(map.keyframes[3].parent, 1u);  // only 3 shares points with 2's parent
  EXPECT_EQ(map.keyframes[4].parent, 3u);  // then 4 attaches to its strongest reattached neighbour
  EXPECT_EQ(map.keyframes[1].covisible, (std::vector<std::pair<KeyframeId, int>>{{3, 20}}));
  EXPECT_EQ(changes.changed_keyframes, (std::set<KeyframeId>{1, 2, 3, 4}));
}

TEST(RecentPointCulling, PointsSeenOnlyByTheirCreatorAreCulledAfterTwoKeyframes) {
  const auto world = test::make_room(800, 61);
  LocalMapperOptions options;
  options.enable_triangulation = false;
  options.enable_fusion = false;
  options.enable_bundle_adjustment = false;
  options.enable_keyframe_culling = false;
  LocalMapper mapper(world.camera, options);
  test::FrontendEmulator frontend(world);

  auto view1 = test::make_view(world, 1, test::circle_pose(0), 1, exact_level0());
  auto [kf1, points1] = frontend.keyframe(mapper.map(), view1, view1.kf.T_wc);
  ASSERT_GT(points1.size(), 100u);
  mapper.process_keyframe(kf1, points1);
  // Keyframes 2 and 3 observe only the even-indexed half of keyframe 1's points.
  std::set<PointId> kept;
  std::set<PointId> dropped;
  for (std::size_t k = 0; k < points1.size(); ++k) (k % 2 == 0 ? kept : dropped).insert(points1[k].id);
  MapChanges last;
  for (KeyframeId id = 2; id <= 3; ++id) {
    auto view = test::make_view(world, id, test::circle_pose(0), static_cast<unsigned>(id), exact_level0());
    auto [kf, points] = frontend.keyframe(mapper.map(), view, view.kf.T_wc);
    for (auto& p : kf.point_ids) {
      if (dropped.count(p) != 0) p = kNoId;
    }
    last = mapper.process_keyframe(kf, {});
  }
  for (const PointId id : dropped) {
    EXPECT_EQ(mapper.map().point(id), nullptr);
    EXPECT_EQ(last.removed_points.count(id), 1u);
  }
  for (const PointId id : kept) ASSERT_NE(mapper.map().point(id), nullptr);
  EXPECT_EQ(last.counts.culled_points, static_cast<int>(dropped.size()));
}

}  // namespace
}  // namespace heslam

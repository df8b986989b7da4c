// Fusion merges duplicated points of the same world point seen by two keyframes.
#include <gtest/gtest.h>

#include "components/core/mapping/point_fusion.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

TEST(PointFusion, MergesDuplicatesAndKeepsDistinctPoints) {
  const auto world = test::make_room(1500, 71);
  test::ViewOptions view_options;
  view_options.clutter = 0;
  auto view1 = test::make_view(world, 1, test::circle_pose(0), 1, view_options);
  auto view2 = test::make_view(world, 2, test::circle_pose(1), 2, view_options);
  Map map;
  map.keyframes.emplace(1, view1.kf);
  map.keyframes.emplace(2, view2.kf);

  std::map<int, int> index2_of_truth;
  for (std::size_t j = 0; j < view2.truth.size(); ++j) index2_of_truth[view2.truth[j]] = static_cast<int>(j);
  std::uint64_t counter = 0;
  const auto new_point = [&](int truth, KeyframeId kf, int index) {
    MapPoint point;
    point.id = make_id(kFrontendTag, ++counter);
    point.p_w = world.points_w[static_cast<std::size_t>(truth)];
    point.reference_kf = kf;
    const PointId id = point.id;
    map.points.emplace(id, point);
    add_observation(map, id, kf, index);
    return id;
  };
  int duplicates = 0;
  std::vector<std::pair<int, int>> duplicated_pairs;  // (index in kf1, index in kf2)
  for (std::size_t i = 0; i < view1.truth.size(); ++i) {
    const int t = view1.truth[i];
    const auto it = index2_of_truth.find(t);
    if (it == index2_of_truth.end()) continue;
    if (t % 2 == 0) {  // one shared point: gives the two keyframes their covisibility edge
      const PointId id = new_point(t, 1, static_cast<int>(i));
      add_observation(map, id, 2, it->second);
    } else {  // the same world point mapped twice
      new_point(t, 1, static_cast<int>(i));
      new_point(t, 2, it->second);
      duplicated_pairs.emplace_back(static_cast<int>(i), it->second);
      ++duplicates;
    }
  }
  for (auto& [id, point] : map.points) update_point_statistics(map, id);
  update_connections(map, 1, CovisibilityOptions{});
  update_connections(map, 2, CovisibilityOptions{});
  ASSERT_GT(duplicates, 50);
  const std::size_t points_before = map.points.size();

  MapChanges changes;
  const int fused = fuse_with_neighbours(map, 2, world.camera, FusionOptions{}, changes);
  int merged_pairs = 0;
  for (const auto& [i, j] : duplicated_pairs) {
    const PointId a = map.keyframes.at(1).point_ids[static_cast<std::size_t>(i)];
    const PointId b = map.keyframes.at(2).point_ids[static_cast<std::size_t>(j)];
    if (a != kNoId && a == b) ++merged_pairs;
  }
  EXPECT_GT(merged_pairs, static_cast<int>(0.95 * duplicates));
  EXPECT_GE(fused, merged_pairs);
  EXPECT_EQ(map.points.size(), points_before - changes.removed_points.size());
  EXPECT_EQ(static_cast<int>(changes.removed_points.size()), merged_pairs);
  // No point was merged with a different world point.
  for (const auto& [id, point] : map.points) {
    std::set<int> truths;
    for (const auto& [kf_id, index] : point.observations) {
      truths.insert((kf_id == 1 ? view1 : view2).truth[static_cast<std::size_t>(index)]);
    }
    EXPECT_EQ(truths.size(), 1u) << "point " << id;
  }
}

}  // namespace
}  // namespace heslam

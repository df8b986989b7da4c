// Triangulation on synthetic correspondences with known 3D points.
#include <gtest/gtest.h>

#include "components/core/mapping/covisibility.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/triangulation.hpp"
#include "components/core/mapping/triangulation_search.hpp"
#include "tests/mapping/synthetic_world.hpp"

namespace heslam {
namespace {

TEST(Triangulation, LinearIsExactWithoutNoise) {
  Pose3 T_wc2 = Pose3::Identity();
  T_wc2.translation() = Eigen::Vector3d(0.5, 0.1, 0.0);
  T_wc2.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d p_w(0.3, -0.2, 4.0);
  const Pose3 T_cw1 = Pose3::Identity();
  const Pose3 T_cw2 = T_wc2.inverse();
  const Eigen::Vector3d p1 = T_cw1 * p_w;
  const Eigen::Vector3d p2 = T_cw2 * p_w;
  const auto result = triangulate_linear(T_cw1, T_cw2, p1.hnormalized(), p2.hnormalized());
  ASSERT_TRUE(result.has_value());
  EXPECT_LT((*result - p_w).norm(), 1e-9);
}

// Two monocular views of the room (no stereo): every recovered point must lie near its world point.
TEST(Triangulation, CreateNewPointsRecoversWorldPoints) {
  const auto world = test::make_room(1500, 7);
  test::ViewOptions view_options;
  view_options.stereo_fraction = 0.0;
  view_options.pixel_noise_px = 0.3;
  Pose3 T_wc2 = test::circle_pose(0);
  T_wc2.translation() += Eigen::Vector3d(0.4, 0.0, 0.0);  // 40 cm sideways: ~5-8 deg parallax at 3-4 m
  auto view1 = test::make_view(world, 1, test::circle_pose(0), 11, view_options);
  auto view2 = test::make_view(world, 2, T_wc2, 12, view_options);

  Map map;
  map.keyframes.emplace(1, view1.kf);
  map.keyframes.emplace(2, view2.kf);
  // A covisibility edge (normally from shared points) so kf 2 is kf 1's neighbour.
  map.keyframes[1].covisible = {{2, 100}};
  map.keyframes[2].covisible = {{1, 100}};

  TriangulationOptions options;
  std::uint64_t counter = 0;
  const auto created = create_new_points(map, 2, world.camera, options, kMapperTag, counter);
  ASSERT_GT(created.size(), 200u);
  EXPECT_EQ(counter, created.size());

  int correct_match = 0;
  double error_sum = 0.0;
  for (const PointId id : created) {
    const MapPoint& point = map.points.at(id);
    ASSERT_EQ(point.observations.size(), 2u);
    EXPECT_EQ(creator_of(id), kMapperTag);
    int t1 = -1;
    int t2 = -1;
    for (const auto& [kf_id, index] : point.observations) {
      EXPECT_EQ(map.keyframes.at(kf_id).point_ids[static_cast<std::size_t>(index)], id);
      (kf_id == 1 ? t1 : t2) = (kf_id == 1 ? view1 : view2).truth[static_cast<std::size_t>(index)];
    }
    if (t1 >= 0 && t1 == t2) {
      ++correct_match;
      const Eigen::Vector3d& truth = world.points_w[static_cast<std::size_t>(t1)];
      const double depth = (truth - map.keyframes.at(2).T_wc.translation()).norm();
      error_sum += (point.p_w - truth).norm() / depth;
    }
  }
  // Wrong matches that pass every geometric check are rare.
  EXPECT_GT(correct_match, static_cast<int>(0.97 * created.size()));
  EXPECT_LT(error_sum / correct_match, 0.02);  // mean error below 2 % of the distance
}

// With stereo keypoints the stereo point is used when the pair's parallax is smaller: close to truth.
TEST(Triangulation, StereoMatchUsesTheBetterParallax) {
  const auto world = test::make_room(500, 3);
  test::ViewOptions view_options;
  view_options.pixel_noise_px = 0.2;  // stereo depth error ~3 % at 3.5 m
  auto view1 = test::make_view(world, 1, test::circle_pose(0), 5, view_options);
  auto view2 = test::make_view(world, 2, test::circle_pose(1), 6, view_options);
  TriangulationOptions options;
  int checked = 0;
  for (std::size_t i = 0; i < view1.truth.size() && checked < 50; ++i) {
    const int t = view1.truth[i];
    if (t < 0 || !view1.kf.features.has_stereo(i)) continue;
    const auto j = std::find(view2.truth.begin(), view2.truth.end(), t) - view2.truth.begin();
    if (j == static_cast<long>(view2.truth.size())) continue;
    const auto p_w =
        triangulate_match(view1.kf, static_cast<int>(i), view2.kf, static_cast<int>(j), world.camera, options);
    if (!p_w) continue;
    const Eigen::Vector3d& truth = world.points_w[static_cast<std::size_t>(t)];
    EXPECT_LT((*p_w - truth).norm(), 0.05 * truth.norm() + 0.05);
    ++checked;
  }
  EXPECT_GE(checked, 40);
}

TEST(Triangulation, RejectsPointsBehindACamera) {
  PinholeStereo camera = test::euroc_like_camera();
  Keyframe kf1;
  kf1.id = 1;
  Keyframe kf2;
  kf2.id = 2;
  kf2.T_wc.translation() = Eigen::Vector3d(1.0, 0.0, 0.0);
  // Rays that only meet behind both cameras: left camera looks right-outwards, right one left-outwards.
  for (Keyframe* kf : {&kf1, &kf2}) {
    kf->features.keypoints.push_back(Keypoint{});
    kf->features.descriptors.push_back(Descriptor{});
    kf->features.u_right_px.push_back(kNoStereo);
    kf->features.depth_m.push_back(kNoStereo);
    kf->point_ids.push_back(kNoId);
  }
  kf1.features.keypoints[0].u_px = static_cast<float>(camera.cx_px - 100);
  kf1.features.keypoints[0].v_px = static_cast<float>(camera.cy_px);
  kf2.features.keypoints[0].u_px = static_cast<float>(camera.cx_px + 100);
  kf2.features.keypoints[0].v_px = static_cast<float>(camera.cy_px);
  EXPECT_FALSE(triangulate_match(kf1, 0, kf2, 0, camera, TriangulationOptions{}).has_value());
}

TEST(TriangulationSearch, MatchesAreEpipolarAndMostlyCorrect) {
  const auto world = test::make_room(1500, 9);
  auto view1 = test::make_view(world, 1, test::circle_pose(0), 21);
  auto view2 = test::make_view(world, 2, test::circle_pose(2), 22);
  const auto matches = search_for_triangulation(view1.kf, view2.kf, world.camera, TriangulationOptions{});
  ASSERT_GT(matches.size(), 100u);
  int correct = 0;
  for (const auto& [i, j] : matches) {
    const int t = view1.truth[static_cast<std::size_t>(i)];
    if (t >= 0 && t == view2.truth[static_cast<std::size_t>(j)]) ++correct;
  }
  EXPECT_GT(correct, static_cast<int>(0.95 * matches.size()));
}

TEST(TriangulationSearch, RotationHistogramDropsInconsistentMatches) {
  std::vector<std::pair<int, int>> matches;
  std::vector<float> rotation;
  for (int m = 0; m < 40; ++m) {
    matches.emplace_back(m, m);
    rotation.push_back(m < 37 ? 1.f : 180.f);  // 37 agree, 3 (under a tenth) are off by 180 deg
  }
  const auto kept = keep_consistent_rotation(matches, rotation);
  EXPECT_EQ(kept.size(), 37u);
}

}  // namespace
}  // namespace heslam

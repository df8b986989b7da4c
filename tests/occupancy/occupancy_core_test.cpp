// The occupancy core with exact small geometry: voxel traversal, log-odds fusion with free space by
// ray casting, the 2D grid's band and its map_server files, keyframe-anchored clouds that move with
// their keyframe, dense stereo depth of a pair with a known disparity, and its multi-view refinement
// on a textured plane seen from known poses.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "components/core/occupancy/dense_stereo.hpp"
#include "components/core/occupancy/multiview_depth.hpp"
#include "components/core/occupancy/occupancy_grid.hpp"
#include "components/core/occupancy/occupancy_map.hpp"
#include "components/core/occupancy/voxel_map.hpp"

namespace heslam {
namespace {

std::filesystem::path temp_dir(const std::string& name) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("heslam_occupancy_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::vector<VoxelIndex> traversed(const VoxelMap& map, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  std::vector<VoxelIndex> out;
  map.traverse(a, b, [&](const VoxelIndex& v) {
    out.push_back(v);
    return true;
  });
  return out;
}

TEST(VoxelMap, TraversesAnAxisRayVoxelByVoxel) {
  const VoxelMap map;  // 5 cm
  const auto voxels = traversed(map, {0.025, 0.025, 0.025}, {0.225, 0.025, 0.025});
  ASSERT_EQ(voxels.size(), 5u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(voxels[i], (VoxelIndex{i, 0, 0}));
  // Negative direction, negative indices: voxel -1 is [-0.05, 0).
  const auto back = traversed(map, {0.01, 0.01, 0.01}, {-0.11, 0.01, 0.01});
  ASSERT_EQ(back.size(), 4u);
  EXPECT_EQ(back.front(), (VoxelIndex{0, 0, 0}));
  EXPECT_EQ(back.back(), (VoxelIndex{-3, 0, 0}));
}

TEST(VoxelMap, TraversesADiagonalRayThroughFaceNeighbours) {
  const VoxelMap map;
  // From voxel (0,0,0) to voxel (3,2,0): each step crosses one face, so |dx| + |dy| + 1 voxels, each a
  // face neighbour of the previous one.
  const auto voxels = traversed(map, {0.01, 0.02, 0.025}, {0.17, 0.12, 0.025});
  ASSERT_EQ(voxels.size(), 6u);
  EXPECT_EQ(voxels.back(), (VoxelIndex{3, 2, 0}));
  for (std::size_t k = 1; k < voxels.size(); ++k) {
    EXPECT_EQ(std::abs(voxels[k].x - voxels[k - 1].x) + std::abs(voxels[k].y - voxels[k - 1].y), 1);
  }
}

TEST(VoxelMap, HitEndsTheRayFreeBeforeIt) {
  VoxelMapOptions options;
  options.free_margin_m = 0.0;  // OctoMap's rays: free up to the hit's voxel
  VoxelMap map(options);
  const std::vector<Eigen::Vector3f> point{{0.525f, 0.025f, 0.025f}};
  EXPECT_EQ(map.integrate({0.025, 0.025, 0.025}, point), 1u);
  for (int i = 0; i < 10; ++i) {
    EXPECT_FLOAT_EQ(map.log_odds({i, 0, 0}), map.options().miss_log_odds) << i;
    EXPECT_TRUE(map.free({i, 0, 0}));
  }
  EXPECT_FLOAT_EQ(map.log_odds({10, 0, 0}), map.options().hit_log_odds);
  EXPECT_TRUE(map.occupied({10, 0, 0}));
  EXPECT_FALSE(map.observed({11, 0, 0}));
  EXPECT_EQ(map.size(), 11u);
  // Clamped: many hits stop at max_log_odds; a NaN point is not used.
  for (int k = 0; k < 10; ++k) map.integrate({0.025, 0.025, 0.025}, point);
  EXPECT_FLOAT_EQ(map.log_odds({10, 0, 0}), map.options().max_log_odds);
  const std::vector<Eigen::Vector3f> bad{{NAN, 0.f, 0.f}};
  EXPECT_EQ(map.integrate({0, 0, 0}, bad), 0u);
}

TEST(VoxelMap, FreeSpaceEndsTheMarginBeforeTheHit) {
  VoxelMap map;  // free_margin_m 0.2: a ray to x = 0.525 is free up to x = 0.325 (voxel 6), voxels 7..9 untouched
  ASSERT_DOUBLE_EQ(map.options().free_margin_m, 0.2);
  const std::vector<Eigen::Vector3f> point{{0.525f, 0.025f, 0.025f}};
  EXPECT_EQ(map.integrate({0.025, 0.025, 0.025}, point), 1u);
  for (int i = 0; i <= 6; ++i) EXPECT_TRUE(map.free({i, 0, 0})) << i;
  for (int i = 7; i <= 9; ++i) EXPECT_FALSE(map.observed({i, 0, 0})) << i;
  EXPECT_TRUE(map.occupied({10, 0, 0}));
  // A point nearer than the margin: its hit only.
  VoxelMap near;
  EXPECT_EQ(near.integrate({0.025, 0.025, 0.025}, std::vector<Eigen::Vector3f>{{0.175f, 0.025f, 0.025f}}), 1u);
  EXPECT_EQ(near.size(), 1u);
  EXPECT_TRUE(near.occupied({3, 0, 0}));
}

TEST(VoxelMap, OneUpdatePerVoxelPerImage) {
  VoxelMap map;
  // Two points in one voxel, the second ray passing the first's voxel: one hit, no miss on it.
  const std::vector<Eigen::Vector3f> points{{0.51f, 0.02f, 0.02f}, {0.52f, 0.03f, 0.03f}, {0.80f, 0.02f, 0.02f}};
  map.integrate({0.025, 0.025, 0.025}, points);
  EXPECT_FLOAT_EQ(map.log_odds({10, 0, 0}), map.options().hit_log_odds);
  EXPECT_FLOAT_EQ(map.log_odds({5, 0, 0}), map.options().miss_log_odds);
  EXPECT_FLOAT_EQ(map.log_odds({16, 0, 0}), map.options().hit_log_odds);
}

// A wall of points on the plane x = 1.02 seen from the origin (z is up in the voxel frame).
std::vector<Eigen::Vector3f> wall_points(double x) {
  std::vector<Eigen::Vector3f> points;
  for (double y = -0.99; y < 1.0; y += 0.02) {
    for (double z = -0.29; z < 0.3; z += 0.02) points.emplace_back(x, y, z);
  }
  return points;
}

TEST(OccupancyGrid, WallIsOccupiedSpaceBeforeItFree) {
  VoxelMap map;
  map.integrate({0.025, 0.025, 0.025}, wall_points(1.02));
  const OccupancyGrid grid = OccupancyGrid::from_voxels(map, GridBand{-0.3, 0.3});
  // Cells i = 20 (x in [1.0, 1.05)) for y in [-1, 1) are the wall: 40 of them, all occupied.
  for (int j = -20; j < 20; ++j) EXPECT_EQ(grid.at(20, j), CellState::kOccupied) << j;
  EXPECT_EQ(grid.count(CellState::kOccupied), 40u);
  EXPECT_EQ(grid.at(21, 0), CellState::kUnknown);  // behind the wall
  EXPECT_EQ(grid.at(10, 0), CellState::kFree);
  EXPECT_EQ(grid.at(0, 0), CellState::kFree);
  // A band above the points' heights sees only the rays' free space (z in [0.35, 0.5]: none reach it).
  const OccupancyGrid above = OccupancyGrid::from_voxels(map, GridBand{0.35, 0.5});
  EXPECT_EQ(above.count(CellState::kOccupied), 0u);
}

TEST(OccupancyGrid, MapServerFilesRoundTripCellByCell) {
  OccupancyGrid grid(0.05);
  grid.set(-3, 2, CellState::kOccupied);
  grid.set(4, -1, CellState::kFree);
  grid.set(0, 0, CellState::kOccupied);
  const auto dir = temp_dir("roundtrip");
  grid.write_map_server(dir / "map");
  std::ifstream yaml(dir / "map.yaml");
  const std::string text((std::istreambuf_iterator<char>(yaml)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("image: map.pgm"), std::string::npos);
  EXPECT_NE(text.find("origin: [-0.15"), std::string::npos) << text;
  EXPECT_NE(text.find("negate: 0"), std::string::npos);
  EXPECT_NE(text.find("occupied_thresh: 0.65"), std::string::npos);
  EXPECT_NE(text.find("free_thresh: 0.196"), std::string::npos);
  // 8 x 4 pixels: i -3..4, j -1..2.
  std::ifstream pgm(dir / "map.pgm", std::ios::binary);
  std::string magic;
  std::getline(pgm, magic);
  EXPECT_EQ(magic, "P5");
  const OccupancyGrid back = OccupancyGrid::read_map_server(dir / "map.yaml");
  EXPECT_EQ(back.cells(), grid.cells());
  std::filesystem::remove_all(dir);
}

TEST(OccupancyGrid, ComparesOccupiedCellsByIoU) {
  OccupancyGrid truth(0.05);
  OccupancyGrid grid(0.05);
  for (int i = 0; i < 9; ++i) {
    truth.set(i, 0, CellState::kOccupied);
    grid.set(i, 0, CellState::kOccupied);
  }
  truth.set(9, 0, CellState::kOccupied);
  grid.set(9, 0, CellState::kFree);  // a free cell inside a wall
  grid.set(5, 5, CellState::kOccupied);
  const GridAgreement a = compare(grid, truth);
  EXPECT_EQ(a.truth_occupied, 10u);
  EXPECT_EQ(a.grid_occupied, 10u);
  EXPECT_EQ(a.both_occupied, 9u);
  EXPECT_DOUBLE_EQ(a.occupied_iou, 9.0 / 11.0);
  EXPECT_EQ(a.free_in_truth_occupied, 1u);
  // Where they disagree: the grid's extra cell is 5 cells from the truth's, the missed one next to the grid's.
  EXPECT_EQ(a.extra_at[0] + a.extra_at[1], 0u);
  EXPECT_EQ(a.extra_at[2], 1u);
  EXPECT_EQ(a.missed_at[0], 1u);
  EXPECT_EQ(a.missed_at[1] + a.missed_at[2], 0u);
  EXPECT_THROW(compare(grid, OccupancyGrid(0.1)), std::invalid_argument);
}

TEST(OccupancyMap, KeyframeCloudMovesWithItsKeyframe) {
  OccupancyMapOptions options;
  options.up = UpAxis::kZ;
  options.band = {-0.3, 0.3};
  OccupancyMap map(options);
  map.add_cloud(7, KeyframeCloud{100, wall_points(1.02), 0.f, {}});
  EXPECT_EQ(map.fused(), 0u);  // no pose yet
  Pose3 T_wc = Pose3::Identity();
  T_wc.translation() = Eigen::Vector3d(0.025, 0.025, 0.025);
  ASSERT_TRUE(map.set_pose(7, T_wc));
  map.fuse_pending();
  EXPECT_EQ(map.fused(), 1u);
  EXPECT_EQ(map.grid().at(20, 0), CellState::kOccupied);  // x = 1.045
  // The mapper refines the pose by +0.5 m in x: the wall follows, the old one is gone.
  T_wc.translation().x() += 0.5;
  ASSERT_TRUE(map.set_pose(7, T_wc));
  EXPECT_TRUE(map.stale());
  map.rebuild_if_stale();
  const OccupancyGrid moved = map.grid();
  EXPECT_EQ(moved.at(30, 0), CellState::kOccupied);
  EXPECT_NE(moved.at(20, 0), CellState::kOccupied);
  // A NaN pose is refused; a culled keyframe leaves the map.
  Pose3 bad = T_wc;
  bad.translation().x() = NAN;
  EXPECT_FALSE(map.set_pose(7, bad));
  map.cull(7);
  map.rebuild_if_stale();
  EXPECT_EQ(map.grid().count(CellState::kOccupied), 0u);
  map.add_cloud(7, KeyframeCloud{100, wall_points(1.02), 0.f, {}});
  EXPECT_FALSE(map.has_cloud(7));
}

// A loop: the same wall seen at the start (keyframes 1-3, exact poses) and again at the loop's end by
// keyframes 10-12 whose first poses drifted 0.2 m (4 cells) towards it: their copy of the wall lies
// 0.2 m behind it. As fused at those first poses the grid has the wall twice (IoU 0.5 against the one
// wall); the loop correction moves 10-12 back, and the map fused again has the wall once, where it is
// (IoU 1), nothing carved out of it.
TEST(OccupancyMap, LoopCorrectionRemovesTheDoubledWall) {
  OccupancyMapOptions options;
  options.up = UpAxis::kZ;
  options.band = {-0.3, 0.3};
  OccupancyMap map(options);
  OccupancyGrid truth(0.05);
  for (int j = -20; j < 20; ++j) truth.set(20, j, CellState::kOccupied);  // x in [1.0, 1.05)
  auto pose = [](double x, double y) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(x, y, 0.025);
    return T;
  };
  const std::vector<Eigen::Vector3f> wall = wall_points(1.02);
  std::vector<Eigen::Vector3f> seen_from(wall.size());
  for (const std::uint64_t id : {1, 2, 3, 10, 11, 12}) {
    const double y = 0.005 + 0.1 * static_cast<double>(id % 3);  // the camera's place along the wall
    const double x = 0.025 + (id >= 10 ? 0.2 : 0.0);             // the drifted ones: 0.2 m nearer in their first pose
    // The cloud as the camera at its true place sees the wall (its camera frame).
    for (std::size_t k = 0; k < wall.size(); ++k)
      seen_from[k] = wall[k] - Eigen::Vector3f(0.025f, static_cast<float>(y), 0.025f);
    ASSERT_TRUE(map.set_pose(id, pose(x, y)));
    map.add_cloud(id, KeyframeCloud{static_cast<std::int64_t>(id), seen_from, 0.f, {}});
  }
  map.rebuild();
  const GridAgreement before = compare(map.grid(), truth);
  EXPECT_EQ(before.both_occupied, 40u);
  EXPECT_EQ(before.grid_occupied, 80u);  // the wall and its copy 4 cells behind it
  EXPECT_DOUBLE_EQ(before.occupied_iou, 0.5);
  EXPECT_EQ(map.grid().at(24, 0), CellState::kOccupied);
  // The correction (the loop closer's, through the mapper's keyframe states): 10-12 where they were.
  for (const std::uint64_t id : {10, 11, 12}) {
    ASSERT_TRUE(map.set_pose(id, pose(0.025, 0.005 + 0.1 * static_cast<double>(id % 3))));
  }
  EXPECT_TRUE(map.stale());
  map.rebuild_if_stale();
  const GridAgreement after = compare(map.grid(), truth);
  EXPECT_DOUBLE_EQ(after.occupied_iou, 1.0);
  EXPECT_EQ(after.free_in_truth_occupied, 0u);
  EXPECT_EQ(map.grid().at(24, 0), CellState::kUnknown);  // never seen: behind the wall
}

TEST(OccupancyMap, MinusYUpGridIsTheCamerasGroundPlane) {
  // Camera convention (x right, y down, z forward): a wall 1 m ahead is the grid row y = 1 m.
  OccupancyMap map(OccupancyMapOptions{});
  std::vector<Eigen::Vector3f> points;
  for (double x = -0.49; x < 0.5; x += 0.02) {
    for (double y = -0.29; y < 0.3; y += 0.02) points.emplace_back(x, y, 1.02);
  }
  map.add_cloud(1, KeyframeCloud{0, points, 0.f, {}});
  map.set_pose(1, Pose3::Identity());
  map.fuse_pending();
  const OccupancyGrid grid = map.grid();
  for (int i = -10; i < 10; ++i) EXPECT_EQ(grid.at(i, 20), CellState::kOccupied) << i;
  EXPECT_EQ(grid.at(0, 10), CellState::kFree);
}

TEST(OccupancyMap, RebuildIsIndependentOfArrivalOrder) {
  auto build = [](bool reversed) {
    OccupancyMapOptions options;
    options.up = UpAxis::kZ;
    OccupancyMap map(options);
    std::vector<std::uint64_t> ids{1, 2, 3};
    if (reversed) std::reverse(ids.begin(), ids.end());
    for (const std::uint64_t id : ids) {
      Pose3 T = Pose3::Identity();
      T.translation() = Eigen::Vector3d(0.1 * id, 0.03 * id, 0.0);
      map.set_pose(id, T);
      map.add_cloud(id, KeyframeCloud{0, wall_points(1.0 + 0.01 * id), 0.f, {}});
      map.fuse_pending();
    }
    map.rebuild();
    return map.grid().cells();
  };
  EXPECT_EQ(build(false), build(true));
}

// Stereo-like noise: ten images of the wall at x = 1.02, each placed 6 cm (more than a cell) in front of or
// behind it in turn, with the wall's normal. A hit per point makes a fringe two cells thick and never
// hits the wall's own voxel (log-odds below); the TSDF averages the distances and finds the wall's voxel
// only, and no column of the wall or the fringe is called free.
TEST(OccupancyGrid, TsdfAveragesNoisyDepthToTheWallWhereHitsMakeAFringe) {
  auto fuse = [](FusionModel model) {
    VoxelMapOptions options;
    options.model = model;
    options.tsdf_truncation_m = 0.15;
    options.tsdf_occupied_m = 0.03;
    options.tsdf_min_weight = 0.5;
    VoxelMap map(options);
    for (int k = 0; k < 10; ++k) {
      const std::vector<Eigen::Vector3f> points = wall_points(k % 2 == 0 ? 0.96 : 1.08);
      const std::vector<float> sigmas(points.size(), 0.03f);
      const std::vector<Eigen::Vector3f> normals(points.size(), Eigen::Vector3f(-1.f, 0.f, 0.f));
      EXPECT_EQ(map.integrate({0.025, 0.025, 0.025}, points, sigmas, normals), points.size());
    }
    return OccupancyGrid::from_voxels(map, GridBand{-0.3, 0.3});
  };
  const OccupancyGrid tsdf = fuse(FusionModel::kTsdf);
  const OccupancyGrid hits = fuse(FusionModel::kLogOdds);
  for (int j = -20; j < 20; ++j) {
    EXPECT_EQ(tsdf.at(20, j), CellState::kOccupied) << j;  // x in [1.0, 1.05): the wall
    if (j == -20 || j == 19) continue;                     // the wall's ends (y = +-1): fewer points to average
    for (const int i : {18, 19, 21}) EXPECT_EQ(tsdf.at(i, j), CellState::kUnknown) << i << " " << j;
    EXPECT_EQ(hits.at(19, j), CellState::kOccupied) << j;  // the fringe, and the wall's voxel never hit
    EXPECT_EQ(hits.at(21, j), CellState::kOccupied) << j;
    EXPECT_EQ(hits.at(20, j), CellState::kUnknown) << j;
  }
  for (int i = 2; i < 15; ++i) EXPECT_EQ(tsdf.at(i, 0), CellState::kFree) << i;
}

// The zero crossing: a wall at x = 1.048, 2 mm before the border of cells 20 and 21, seen exactly. Both
// voxels' centres are within tsdf_occupied_m (3 cm) of it, so the threshold marks a wall two cells thick;
// the zero crossing marks the one it lies in (cell 20: 2.3 cm in front of its centre, 2.7 cm behind 21's).
TEST(OccupancyGrid, TsdfZeroCrossingMarksTheVoxelTheSurfaceLiesIn) {
  auto fuse = [](bool zero_crossing) {
    VoxelMapOptions options;
    options.model = FusionModel::kTsdf;
    options.tsdf_truncation_m = 0.15;
    options.tsdf_occupied_m = 0.03;
    options.tsdf_zero_crossing = zero_crossing;
    VoxelMap map(options);
    const std::vector<Eigen::Vector3f> points = wall_points(1.048);
    const std::vector<Eigen::Vector3f> normals(points.size(), Eigen::Vector3f(-1.f, 0.f, 0.f));
    for (int k = 0; k < 3; ++k) map.integrate({0.025, 0.025, 0.025}, points, {}, normals);
    return OccupancyGrid::from_voxels(map, GridBand{-0.3, 0.3});
  };
  const OccupancyGrid crossing = fuse(true);
  const OccupancyGrid threshold = fuse(false);
  for (int j = -15; j < 15; ++j) {
    EXPECT_EQ(crossing.at(20, j), CellState::kOccupied) << j;
    EXPECT_NE(crossing.at(21, j), CellState::kOccupied) << j;
    EXPECT_NE(crossing.at(19, j), CellState::kOccupied) << j;
    EXPECT_EQ(threshold.at(20, j), CellState::kOccupied) << j;
    EXPECT_EQ(threshold.at(21, j), CellState::kOccupied) << j;
  }
}

// The plane fit (tsdf_fit_radius): a wall at x = 1.040 (cell 20 is [1.00, 1.05)) seen in 4 images, each
// with a depth error that is the same over a 5 cm patch (as stereo's is correlated over a window) and
// 1.5 cm rms between patches. A voxel's own average keeps ~0.8 cm of it, enough to put some columns'
// crossing in cell 21 (the wall 1 cm from the border); fitted over 27 voxels the wall is in cell 20
// in every column and nowhere else.
TEST(OccupancyGrid, TsdfPlaneFitPlacesANoisyWallInItsCell) {
  auto fuse = [](int fit_radius) {
    VoxelMapOptions options;
    options.model = FusionModel::kTsdf;
    options.tsdf_truncation_m = 0.15;
    options.tsdf_occupied_m = 0.04;
    options.tsdf_min_weight = 0.5;
    options.tsdf_zero_crossing = true;
    options.tsdf_fit_radius = fit_radius;
    VoxelMap map(options);
    std::mt19937 random(36);
    std::normal_distribution<double> patch_error(0.0, 0.015);
    for (int image = 0; image < 4; ++image) {
      std::map<std::pair<int, int>, double> error;  // per 5 cm patch of the wall
      std::vector<Eigen::Vector3f> points;
      for (const Eigen::Vector3f& p : wall_points(1.040)) {
        const std::pair<int, int> patch{static_cast<int>(std::floor(p.y() / 0.05)),
                                        static_cast<int>(std::floor(p.z() / 0.05))};
        if (!error.count(patch)) error[patch] = patch_error(random);
        points.emplace_back(p.x() + static_cast<float>(error[patch]), p.y(), p.z());
      }
      const std::vector<Eigen::Vector3f> normals(points.size(), Eigen::Vector3f(-1.f, 0.f, 0.f));
      map.integrate({0.025, 0.025, 0.025}, points, {}, normals);
    }
    return OccupancyGrid::from_voxels(map, GridBand{-0.25, 0.25});
  };
  const OccupancyGrid own = fuse(0);
  const OccupancyGrid fitted = fuse(1);
  int misplaced_own = 0;
  // The wall's columns j in [-20, 20); the outermost have neighbours on one side only: still fitted.
  for (int j = -20; j < 20; ++j) {
    EXPECT_EQ(fitted.at(20, j), CellState::kOccupied) << j;
    EXPECT_NE(fitted.at(19, j), CellState::kOccupied) << j;
    EXPECT_NE(fitted.at(21, j), CellState::kOccupied) << j;
    misplaced_own += own.at(21, j) == CellState::kOccupied || own.at(19, j) == CellState::kOccupied;
  }
  EXPECT_GT(misplaced_own, 3) << "the noise must be large enough that a voxel's own average misplaces the wall";
}

// The grid's up from gravity (set_up_direction): a camera pitched 10 deg down, 1.4 m above a floor, a wall
// 4.02 m ahead (both exact points, the camera's frame the world). Along the camera's -y the height band
// (-0.7 .. 0.3 m) is tilted with the camera: beyond ~4 m ahead the floor rises into it and the wall is
// smeared over several cells. Against gravity the band is level: the floor stays out and the wall is the
// one row of cells at 4.02 m (grid y along the level forward direction).
TEST(OccupancyMap, UpFromGravityLevelsTheBand) {
  const double pitch = 10.0 * std::numbers::pi / 180.0;
  // Camera axes in a level frame G (z up, x the level forward): forward pitched down, x right = -y_G.
  const Eigen::Vector3d z_c(std::cos(pitch), 0.0, -std::sin(pitch));
  const Eigen::Vector3d x_c(0.0, -1.0, 0.0);
  const Eigen::Vector3d y_c = z_c.cross(x_c);
  Eigen::Matrix3d R_gc;
  R_gc << x_c, y_c, z_c;
  KeyframeCloud cloud;
  for (double y = -1.0; y < 1.0; y += 0.02) {
    for (double x = 0.5; x < 4.0; x += 0.02)
      cloud.points_c.push_back((R_gc.transpose() * Eigen::Vector3d(x, y, -1.4)).cast<float>());
    for (double z = -1.4; z < 1.0; z += 0.02)
      cloud.points_c.push_back((R_gc.transpose() * Eigen::Vector3d(4.02, y, z)).cast<float>());
  }
  auto grid = [&](bool from_gravity) {
    OccupancyMap map;
    if (from_gravity) {
      EXPECT_TRUE(map.set_up_direction(R_gc.transpose() * Eigen::Vector3d::UnitZ()));
    }
    map.set_pose(1, Pose3::Identity());
    map.add_cloud(1, cloud);
    map.fuse_pending();
    return map.grid();
  };
  const OccupancyGrid level = grid(true);
  const OccupancyGrid tilted = grid(false);
  std::size_t level_off_wall = 0, tilted_off_wall = 0;
  for (const auto& [ij, state] : level.cells()) level_off_wall += state == CellState::kOccupied && ij.second != 80;
  for (const auto& [ij, state] : tilted.cells()) tilted_off_wall += state == CellState::kOccupied && ij.second != 80;
  EXPECT_EQ(level_off_wall, 0u) << "the floor, 1.4 m down, is outside a level band";
  EXPECT_GE(level.count(CellState::kOccupied), 38u);  // the wall's 2 m: 40 cells
  EXPECT_GT(tilted_off_wall, 20u) << "along the pitched camera's -y the floor enters the band";
  // Up along the first camera's -y (no gravity) and a direction that is not a unit vector change nothing.
  OccupancyMap unchanged;
  EXPECT_FALSE(unchanged.set_up_direction(Eigen::Vector3d(0.0, -2.0, 0.0)));
  EXPECT_NEAR(unchanged.angle_to_up(Eigen::Vector3d(0.0, -1.0, 0.0)), 0.0, 1e-12);
  EXPECT_TRUE(unchanged.set_up_direction(Eigen::Vector3d(0.0, -1.0, 0.0)));
  EXPECT_TRUE(unchanged.R_gw().isApprox(OccupancyMap().R_gw(), 1e-12));
}

TEST(OccupancyMap, CloudFilesRoundTripAndRefuseTruncation) {
  const auto dir = temp_dir("cloud");
  KeyframeCloud cloud{123456789, wall_points(1.5), 0.002f, {}};
  cloud.normals_c.assign(cloud.points_c.size(), Eigen::Vector3f(-1.f, 0.f, 0.f));
  cloud.normals_c[17] = Eigen::Vector3f::Zero();
  write_cloud(dir / "kf.cloud", 42, cloud);
  std::uint64_t id = 0;
  const KeyframeCloud back = read_cloud(dir / "kf.cloud", id);
  EXPECT_EQ(id, 42u);
  EXPECT_EQ(back.stamp_ns, cloud.stamp_ns);
  ASSERT_EQ(back.points_c.size(), cloud.points_c.size());
  EXPECT_EQ(back.points_c[17], cloud.points_c[17]);
  EXPECT_EQ(back.sigma_per_m2, cloud.sigma_per_m2);
  EXPECT_EQ(back.normals_c, cloud.normals_c);
  std::filesystem::resize_file(dir / "kf.cloud", std::filesystem::file_size(dir / "kf.cloud") - 5);
  EXPECT_THROW(read_cloud(dir / "kf.cloud", id), std::runtime_error);
  std::filesystem::remove_all(dir);
}

// A multi-view kept view (heslam-occupancy's state folder) reads back exactly; a short or foreign file is refused.
TEST(MultiViewDepth, KeptViewFilesRoundTripAndRefuseTruncation) {
  const auto dir = temp_dir("view");
  KeptView view;
  view.keyframe_id = 77;
  view.sequence = 5;
  view.left = cv::Mat(48, 64, CV_8UC1);
  cv::randu(view.left, 0, 256);
  view.T_wc.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  view.T_wc.translation() = Eigen::Vector3d(0.1, -2.5, 7.25);
  write_view(dir / "77.view", view);
  const KeptView back = read_view(dir / "77.view");
  EXPECT_EQ(back.keyframe_id, 77u);
  EXPECT_EQ(back.sequence, 5u);
  EXPECT_EQ(back.T_wc.matrix(), view.T_wc.matrix());
  ASSERT_EQ(back.left.size(), view.left.size());
  EXPECT_EQ(cv::norm(back.left, view.left, cv::NORM_INF), 0.0);
  std::filesystem::resize_file(dir / "77.view", std::filesystem::file_size(dir / "77.view") - 1);
  EXPECT_THROW(read_view(dir / "77.view"), std::runtime_error);
  write_cloud(dir / "kf.view", 1, KeyframeCloud{0, wall_points(1.0), 0.f, {}});
  EXPECT_THROW(read_view(dir / "kf.view"), std::runtime_error);
  EXPECT_THROW(write_view(dir / "x.view", KeptView{}), std::invalid_argument);
  std::filesystem::remove_all(dir);
}

// A rectified camera of width x height pixels, focal length f_px, principal point at the centre, 0.1 m baseline.
PinholeStereo small_camera(double f_px, int width, int height) {
  PinholeStereo camera;
  camera.fx_px = camera.fy_px = f_px;
  camera.cx_px = 0.5 * width;
  camera.cy_px = 0.5 * height;
  camera.baseline_m = 0.1;
  camera.width_px = width;
  camera.height_px = height;
  return camera;
}

TEST(DenseStereo, KnownDisparityGivesKnownDepth) {
  const PinholeStereo camera = small_camera(400.0, 320, 240);
  // A random texture; the right image is the left shifted 20 px left: disparity 20, depth 400 * 0.1 / 20 = 2 m.
  cv::Mat left(240, 320, CV_8UC1);
  cv::RNG rng(7);
  cv::Mat coarse(60, 80, CV_8UC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 256);
  cv::resize(coarse, left, left.size(), 0, 0, cv::INTER_LINEAR);
  cv::Mat right = cv::Mat::zeros(left.size(), CV_8UC1);
  left.colRange(20, 320).copyTo(right.colRange(0, 300));
  DenseStereoOptions options;
  options.thin_voxel_m = 0.0;
  options.pixel_step = 2;
  const DenseStereo stereo(camera, options);
  const cv::Mat disparity = stereo.disparity(left, right);
  EXPECT_NEAR(disparity.at<float>(120, 160), 20.0f, 0.1f);
  const std::vector<Eigen::Vector3f> cloud = stereo.cloud(left, right);
  ASSERT_GT(cloud.size(), 5000u);
  std::vector<float> depths;
  for (const auto& p : cloud) depths.push_back(p.z());
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  EXPECT_NEAR(depths[depths.size() / 2], 2.0f, 0.01f);
  // Thinned (the default 5 cm): one finite point per cube, at the same depth (every 4th pixel: this
  // smooth texture leaves single pixels ~1 px off, 0.1 m at 2 m, that a cube of few pixels would show).
  DenseStereoOptions thin_options;
  thin_options.pixel_step = 4;
  const DenseStereo thinned(camera, thin_options);
  const std::vector<Eigen::Vector3f> thin_cloud = thinned.cloud(left, right);
  ASSERT_FALSE(thin_cloud.empty());
  for (const auto& p : thin_cloud) {
    ASSERT_TRUE(p.allFinite());
    EXPECT_NEAR(p.z(), 2.0f, 0.06f);
  }
  // Wrong size: one clear error, no crash.
  EXPECT_THROW(stereo.disparity(left(cv::Rect(0, 0, 100, 100)), right), std::runtime_error);
}

// A sub-pixel shift: the pair is an 8x finer random texture shifted 8 x 12.375 fine pixels and area-averaged
// down (each pixel integrates its area), so the true disparity is 12.375 px everywhere. SGBM's value pixel-locks
// (its parabola fit: median absolute error 0.19 px); the refinement brings it to 0.035 px.
TEST(DenseStereo, RefinementFindsASubPixelShift) {
  constexpr int kScale = 8, kWidth = 320, kHeight = 120, kShiftFine = 99;  // 99 / 8 = 12.375 px
  constexpr float kTrue = static_cast<float>(kShiftFine) / kScale;
  const PinholeStereo camera = small_camera(400.0, kWidth, kHeight);
  cv::RNG rng(11);
  cv::Mat coarse(kHeight / 2, kWidth / 2 + 16, CV_32F);
  rng.fill(coarse, cv::RNG::UNIFORM, 0, 255);
  cv::Mat fine;
  cv::resize(coarse, fine, cv::Size((kWidth + 32) * kScale, kHeight * kScale), 0, 0, cv::INTER_CUBIC);
  const auto take = [&](int first_fine_column) {
    cv::Mat out, u8;
    cv::resize(fine.colRange(first_fine_column, first_fine_column + kWidth * kScale), out, cv::Size(kWidth, kHeight), 0,
               0, cv::INTER_AREA);
    out.convertTo(u8, CV_8U);
    return u8;
  };
  // Scene column x shows in the left image at x - 16 px, in the right one at x - 16 - 12.375 px.
  const cv::Mat left = take(16 * kScale), right = take(16 * kScale + kShiftFine);
  DenseStereoOptions sgbm_options;
  DenseStereoOptions refined_options;
  refined_options.refine_iterations = 4;
  const auto median_error = [&](const DenseStereoOptions& options, double& valid) {
    const cv::Mat d = DenseStereo(camera, options).disparity(left, right);
    std::vector<float> errors;
    long n = 0;
    for (int v = 10; v < kHeight - 10; ++v) {
      for (int u = 80; u < kWidth - 10; ++u) {
        ++n;
        if (d.at<float>(v, u) > 0.f) errors.push_back(std::abs(d.at<float>(v, u) - kTrue));
      }
    }
    valid = static_cast<double>(errors.size()) / static_cast<double>(n);
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    return errors[errors.size() / 2];
  };
  double sgbm_valid = 0.0, refined_valid = 0.0;
  const float sgbm_error = median_error(sgbm_options, sgbm_valid);
  const float refined_error = median_error(refined_options, refined_valid);
  std::printf("median |error|: SGBM %.3f px (valid %.2f), refined %.3f px (valid %.2f)\n", sgbm_error, sgbm_valid,
              refined_error, refined_valid);
  EXPECT_GT(refined_valid, 0.9);
  EXPECT_LT(refined_error, 0.05f);
  EXPECT_LT(refined_error, sgbm_error);
  DenseStereoOptions bad;
  bad.refine_radius_px = 0;
  EXPECT_THROW(DenseStereo(camera, bad), std::runtime_error);
}

// A fronto-parallel plane at depth 3 m in the keyframe's frame, textured with smoothed noise (1 cm texels),
// as a camera at T_wc (world = the keyframe's camera) sees it: exact geometry, bilinear texture.
cv::Mat render_plane(const PinholeStereo& camera, const cv::Mat& texture, const Pose3& T_wc) {
  constexpr double kDepth = 3.0, kTexelsPerM = 100.0;
  cv::Mat map_x(camera.height_px, camera.width_px, CV_32F), map_y(camera.height_px, camera.width_px, CV_32F);
  for (int v = 0; v < camera.height_px; ++v) {
    for (int u = 0; u < camera.width_px; ++u) {
      const Eigen::Vector3d ray = T_wc.linear() * camera.unproject(u, v, 1.0);
      const double t = (kDepth - T_wc.translation().z()) / ray.z();
      const Eigen::Vector3d p = T_wc.translation() + t * ray;
      map_x.at<float>(v, u) = static_cast<float>(p.x() * kTexelsPerM + 0.5 * texture.cols);
      map_y.at<float>(v, u) = static_cast<float>(p.y() * kTexelsPerM + 0.5 * texture.rows);
    }
  }
  cv::Mat image;
  cv::remap(texture, image, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  cv::Mat grey;
  image.convertTo(grey, CV_8U);
  return grey;
}

// The plane's disparity is bf / 3 = 10 px everywhere; SGBM's stand-in is 0.4 px too large (a 12 cm bias at
// 3 m) with 0.2 px of noise. Against three earlier keyframes 0.3-0.6 m away (one turned by 2 degrees) and the
// right image, the refinement finds the plane: 91% of the interior pixels refined, median error 0.005 px.
TEST(MultiViewDepth, RefinesABiasedDisparityOfATexturedPlaneToTheTruth) {
  const PinholeStereo camera = small_camera(300.0, 320, 240);
  cv::Mat texture(900, 1200, CV_32F);
  cv::RNG rng(7);
  rng.fill(texture, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 1.5);
  cv::normalize(texture, texture, 20.0, 235.0, cv::NORM_MINMAX);
  const auto pose = [](double x, double y, double yaw_deg) {
    Pose3 T = Pose3::Identity();
    T.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(x, y, 0.0);
    return T;
  };
  const Pose3 T_key = Pose3::Identity();
  const cv::Mat left = render_plane(camera, texture, T_key);
  const cv::Mat right = render_plane(camera, texture, pose(camera.baseline_m, 0.0, 0.0));
  cv::Mat sgbm(camera.height_px, camera.width_px, CV_32F);
  rng.fill(sgbm, cv::RNG::NORMAL, 10.4, 0.2);

  MultiViewDepthOptions options;
  EXPECT_FALSE(options.enabled()) << "off by default";
  options.neighbours = 3;
  MultiViewDepth refiner(camera, options);
  EXPECT_EQ(cv::norm(refiner.refine(sgbm, left, right, T_key), sgbm, cv::NORM_INF), 0.0) << "no view: unchanged";
  for (const Pose3& T : {pose(-0.6, 0.0, 0.0), pose(-0.45, 0.1, 2.0), pose(-0.3, 0.0, 0.0)}) {
    refiner.add_view(render_plane(camera, texture, T), T);
  }
  MultiViewDepthStats stats;
  const cv::Mat refined = refiner.refine(sgbm, left, right, T_key, &stats);
  EXPECT_EQ(stats.views_used, 4u);
  std::vector<float> errors;
  for (int v = 20; v < camera.height_px - 20; ++v) {
    for (int u = 20; u < camera.width_px - 20; ++u) {
      if (refined.at<float>(v, u) != sgbm.at<float>(v, u)) errors.push_back(std::abs(refined.at<float>(v, u) - 10.f));
    }
  }
  const std::size_t interior = static_cast<std::size_t>((camera.height_px - 40) * (camera.width_px - 40));
  ASSERT_GT(errors.size(), interior * 9 / 10) << "most pixels refined";
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  std::printf("multi-view on a plane: %zu of %zu interior pixels refined, median |error| %.4f px, %zu candidates\n",
              errors.size(), interior, errors[errors.size() / 2], stats.candidates);
  EXPECT_LT(errors[errors.size() / 2], 0.02f) << "median |error| (SGBM's stand-in: 0.4 px)";
  EXPECT_EQ(cv::norm(refiner.refine(sgbm, left, right, T_key), refined, cv::NORM_INF), 0.0) << "deterministic";

  MultiViewDepthOptions bad = options;
  bad.passes = 0;
  EXPECT_THROW(MultiViewDepth(camera, bad), std::runtime_error);
}

}  // namespace
}  // namespace heslam

// heslam-occupancy's live outputs without DDS, on known grids: the wire layout of the grid
// (idl/occupancy.idl) against the map_server files of the same grid, the checks a reader applies,
// the cloud's decimation, heslam-ros2-bridge's nav_msgs/OccupancyGrid of it, and heslam-viewer's
// drawing of it in the top view.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "components/core/occupancy/occupancy_grid.hpp"
#include "components/occupancy/occupancy_messages.hpp"
#include "test_support.hpp"
#include "tools/ros2_bridge/ros2_conversions.hpp"
#include "tools/viewer/colours.hpp"
#include "tools/viewer/top_view_renderer.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

// An L-shaped wall with free cells in front of it, away from the origin and partly at negative indices.
OccupancyGrid known_grid() {
  OccupancyGrid grid(0.05);
  for (int i = -3; i <= 6; ++i) grid.set(i, 8, CellState::kOccupied);
  for (int j = 2; j <= 8; ++j) grid.set(-3, j, CellState::kOccupied);
  for (int i = -2; i <= 6; ++i) {
    for (int j = 3; j <= 7; ++j) grid.set(i, j, CellState::kFree);
  }
  return grid;
}

// The grid frame of a map whose up is the world's -y: grid x = world x, grid y = world z.
Pose3 minus_y_up_T_wg() {
  Pose3 T = Pose3::Identity();
  T.linear() << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  return T;
}

struct Pgm {
  int width = 0, height = 0;
  std::vector<std::uint8_t> pixels;
};

Pgm read_pgm(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string magic, comment;
  Pgm pgm;
  int max_value = 0;
  in >> magic;
  in.get();
  if (in.peek() == '#') std::getline(in, comment);
  in >> pgm.width >> pgm.height >> max_value;
  in.get();
  pgm.pixels.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return pgm;
}

// The wire value of a PGM pixel (map_server trinary: 0 occupied, 254 free, 205 unknown).
std::uint8_t wire_of_pixel(std::uint8_t pixel) {
  if (pixel == 0) return heslam_msg_OCCUPANCY_OCCUPIED;
  if (pixel == 254) return heslam_msg_OCCUPANCY_FREE;
  return heslam_msg_OCCUPANCY_UNKNOWN;
}

TEST(OccupancyLiveMessages, GridMessageHasTheMapServerFilesCellsSizeAndOrigin) {
  const OccupancyGrid grid = known_grid();
  const test::ScratchDir dir("occupancy_live_grid");
  grid.write_map_server(dir.path() / "map");
  const Pgm pgm = read_pgm(dir.path() / "map.pgm");
  const occupancy::GridMessage message(grid, minus_y_up_T_wg(), 7, 123456789, 5);
  const msg::OccupancyGrid2D& m = message.get();
  EXPECT_EQ(m.revision, 7u);
  EXPECT_EQ(m.stamp_ns, 123456789);
  EXPECT_EQ(m.keyframes, 5u);
  EXPECT_DOUBLE_EQ(m.resolution_m, 0.05);
  ASSERT_EQ(static_cast<int>(m.width), pgm.width);
  ASSERT_EQ(static_cast<int>(m.height), pgm.height);
  EXPECT_EQ(m.width, 10u);  // i in [-3, 6]
  EXPECT_EQ(m.height, 7u);  // j in [2, 8]
  EXPECT_EQ(m.origin_i, -3);
  EXPECT_EQ(m.origin_j, 2);
  ASSERT_EQ(m.cells._length, m.width * m.height);
  ASSERT_EQ(pgm.pixels.size(), std::size_t{m.width} * m.height);
  // Row 0 of the message is the lowest y, the PGM's last row.
  for (std::uint32_t row = 0; row < m.height; ++row) {
    for (std::uint32_t col = 0; col < m.width; ++col) {
      const std::uint8_t pixel = pgm.pixels[std::size_t{m.height - 1 - row} * m.width + col];
      ASSERT_EQ(m.cells._buffer[std::size_t{row} * m.width + col], wire_of_pixel(pixel)) << row << ", " << col;
    }
  }
  // Read back: the same cells and frame.
  const occupancy::ReceivedGrid back = occupancy::from_message(m);
  EXPECT_EQ(back.grid.cells(), grid.cells());
  EXPECT_LT((back.T_wg.matrix() - minus_y_up_T_wg().matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(OccupancyLiveMessages, EmptyGridIsOneUnknownCellAtTheOriginAsInTheMapServerFiles) {
  const occupancy::GridMessage message(OccupancyGrid(0.05), Pose3::Identity(), 1, 0, 0);
  EXPECT_EQ(message.get().width, 1u);
  EXPECT_EQ(message.get().height, 1u);
  EXPECT_EQ(message.get().origin_i, 0);
  ASSERT_EQ(message.get().cells._length, 1u);
  EXPECT_EQ(message.get().cells._buffer[0], heslam_msg_OCCUPANCY_UNKNOWN);
}

TEST(OccupancyLiveMessages, MalformedGridsAreRefusedWithTheField) {
  const occupancy::GridMessage good(known_grid(), Pose3::Identity(), 1, 0, 1);
  EXPECT_EQ(occupancy::check_grid(good.get()), "");
  msg::OccupancyGrid2D bad = good.get();
  bad.width += 1;  // the cells no longer fill width x height
  EXPECT_NE(occupancy::check_grid(bad).find("field cells"), std::string::npos) << occupancy::check_grid(bad);
  EXPECT_THROW(occupancy::from_message(bad), std::runtime_error);
  bad = good.get();
  bad.resolution_m = std::nan("");
  EXPECT_NE(occupancy::check_grid(bad).find("field resolution_m"), std::string::npos);
  bad = good.get();
  bad.T_wg.position_m[1] = INFINITY;
  EXPECT_NE(occupancy::check_grid(bad).find("field T_wg"), std::string::npos);
  std::vector<std::uint8_t> cells(good.get().cells._buffer, good.get().cells._buffer + good.get().cells._length);
  cells[3] = 42;
  bad = good.get();
  bad.cells._buffer = cells.data();
  EXPECT_NE(occupancy::check_grid(bad).find("value 42"), std::string::npos) << occupancy::check_grid(bad);
}

TEST(OccupancyLiveMessages, CloudIsDecimatedToItsBound) {
  std::vector<Eigen::Vector3f> points;
  for (int k = 0; k < 1000; ++k) points.emplace_back(static_cast<float>(k), 0.f, 1.f);
  EXPECT_EQ(occupancy::decimate(points, 2000).size(), 1000u);
  const std::vector<Eigen::Vector3f> kept = occupancy::decimate(points, 300);  // every 4th
  EXPECT_EQ(kept.size(), 250u);
  EXPECT_EQ(kept[1].x(), 4.f);
  EXPECT_LE(occupancy::decimate(points, 999).size(), 999u);
  EXPECT_TRUE(occupancy::decimate(points, 0).empty());
  const occupancy::CloudMessage message(kept, 1000, 3, 42, 2);
  EXPECT_EQ(message.get().xyz_w_m._length, 3 * 250u);
  EXPECT_EQ(message.get().total_points, 1000u);
  EXPECT_EQ(message.get().xyz_w_m._buffer[3], 4.f);
}

// nav_msgs/OccupancyGrid as the bridge sends it: map_server's values, size and resolution, the data
// in the same rows, and the origin = T_map_world T_wg (cell (origin_i, origin_j)'s corner).
TEST(OccupancyLiveRos2, OccupancyGridHasTheSavedMapsCellsSizeResolutionAndOrigin) {
  const OccupancyGrid grid = known_grid();
  const test::ScratchDir dir("occupancy_live_ros2");
  grid.write_map_server(dir.path() / "map");
  const Pgm pgm = read_pgm(dir.path() / "map.pgm");
  const occupancy::GridMessage heslam_grid(grid, minus_y_up_T_wg(), 1, 2'500'000'000, 3);
  Pose3 T_map_world = Pose3::Identity();
  T_map_world.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  T_map_world.translation() = Eigen::Vector3d(0.4, -0.2, 1.5);
  const ros2::Frames frames;
  const ros2::OccupancyGridMessage ros(heslam_grid.get(), T_map_world, frames);
  const ros2::OccupancyGrid& m = ros.get();
  EXPECT_STREQ(m.header.frame_id, "map");
  EXPECT_EQ(m.header.stamp.sec, 2);
  EXPECT_EQ(m.header.stamp.nanosec, 500'000'000u);
  EXPECT_FLOAT_EQ(m.info.resolution, 0.05f);
  ASSERT_EQ(static_cast<int>(m.info.width), pgm.width);
  ASSERT_EQ(static_cast<int>(m.info.height), pgm.height);
  ASSERT_EQ(m.data._length, pgm.pixels.size());
  for (std::uint32_t row = 0; row < m.info.height; ++row) {
    for (std::uint32_t col = 0; col < m.info.width; ++col) {
      const std::uint8_t pixel = pgm.pixels[std::size_t{m.info.height - 1 - row} * m.info.width + col];
      const int expected = pixel == 0 ? 100 : pixel == 254 ? 0 : -1;
      ASSERT_EQ(m.data._buffer[std::size_t{row} * m.info.width + col], expected) << row << ", " << col;
    }
  }
  // The map_server origin (lower-left corner in the grid frame) carried into map.
  const Eigen::Vector3d origin_g(-3 * 0.05, 2 * 0.05, 0.0);
  const Eigen::Vector3d expected_origin = T_map_world * minus_y_up_T_wg() * origin_g;
  const Eigen::Vector3d origin(m.info.origin.position.x, m.info.origin.position.y, m.info.origin.position.z);
  EXPECT_LT((origin - expected_origin).norm(), 1e-12);
  const Eigen::Quaterniond q(m.info.origin.orientation.w, m.info.origin.orientation.x, m.info.origin.orientation.y,
                             m.info.origin.orientation.z);
  EXPECT_LT((q.toRotationMatrix() - (T_map_world.linear() * minus_y_up_T_wg().linear())).cwiseAbs().maxCoeff(), 1e-12);
}

// heslam-viewer's top view: each known cell drawn in its colour where the projection puts it (x right,
// world z up), unknown cells not at all; the layer key turns it off.
TEST(OccupancyLiveViewer, TopViewDrawsTheGridCellsUnderTheMap) {
  OccupancyGrid grid(0.5);  // big cells: their centres are far from any edge, grid line or label
  grid.set(0, 2, CellState::kOccupied);
  grid.set(1, 2, CellState::kFree);
  grid.set(-1, 1, CellState::kFree);
  viewer::Scene scene;
  scene.occupancy = std::make_shared<const OccupancyGrid>(grid);
  scene.occupancy_T_wg = minus_y_up_T_wg();
  // The fitted area: a trajectory from (-1, 0, 0) to (1.5, 0, 1.5) (world x, z).
  scene.trajectory_w = {Eigen::Vector3d(-1.0, 0.0, 0.0), Eigen::Vector3d(1.5, 0.0, 1.5)};
  viewer::Layers layers;
  layers.trajectory = false;
  const viewer::TopView view = viewer::TopViewRenderer(cv::Size(600, 600)).render(scene, layers);
  EXPECT_EQ(view.occupancy_cells_drawn, 3u);
  // The projection's centre is the middle of the fitted area: world (0.25, 0.75) at column 300.
  const double s = view.scale_px_per_m;
  auto pixel_at = [&](double x_m, double z_m) {
    // Row of z: as the renderer's projection (legend 18 px, margin 30 px, scale bar room 24 px).
    const double fitted_height = 600 - 2 * 30 - 18 - 24;
    const double row = 18 + 30 + 0.5 * fitted_height - (z_m - 0.75) * s;
    const double column = 300 + (x_m - 0.25) * s;
    return view.image.at<cv::Vec3b>(static_cast<int>(std::lround(row)), static_cast<int>(std::lround(column)));
  };
  auto colour = [](const cv::Scalar& c) {
    return cv::Vec3b(static_cast<uchar>(c[0]), static_cast<uchar>(c[1]), static_cast<uchar>(c[2]));
  };
  // Cell (0, 2): grid x [0, 0.5), grid y [1, 1.5) = world z: centre (0.25, 1.25) — occupied. Cell (1, 2):
  // centre (0.75, 1.25) free; cell (-1, 1): centre (-0.25, 0.75) free; (0, 1) unknown: background.
  EXPECT_EQ(pixel_at(0.25 + 0.1, 1.25 + 0.1), colour(viewer::colours::kOccupiedCell));
  EXPECT_EQ(pixel_at(0.75 + 0.1, 1.25 + 0.1), colour(viewer::colours::kFreeCell));
  EXPECT_EQ(pixel_at(-0.25 + 0.1, 0.75 + 0.1), colour(viewer::colours::kFreeCell));
  EXPECT_EQ(pixel_at(0.25 + 0.1, 0.75 + 0.1), colour(viewer::colours::kBackground));

  layers.toggle('o');
  const viewer::TopView without = viewer::TopViewRenderer(cv::Size(600, 600)).render(scene, layers);
  EXPECT_EQ(without.occupancy_cells_drawn, 0u);
  const double row = 18 + 30 + 0.5 * (600 - 2 * 30 - 18 - 24) - (1.35 - 0.75) * without.scale_px_per_m;
  const double column = 300 + (0.35 - 0.25) * without.scale_px_per_m;
  EXPECT_EQ(without.image.at<cv::Vec3b>(static_cast<int>(std::lround(row)), static_cast<int>(std::lround(column))),
            colour(viewer::colours::kBackground));
}

}  // namespace
}  // namespace heslam

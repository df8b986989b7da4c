// KITTI odometry pose format: 12 numbers per line (row-major 3x4 T_wc), optionally preceded by the
// frame index (kitti-odom-eval's 13-column variant).
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "tools/eval/line_reader.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::eval {

namespace {

constexpr std::size_t kPoseColumns = 12;
constexpr std::size_t kIndexedPoseColumns = 13;

bool ids_are_line_order(const Trajectory& trajectory) {
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    if (trajectory.frame_ids[i] != static_cast<std::int64_t>(i)) return false;
  }
  return true;
}

}  // namespace

Trajectory read_kitti(const std::filesystem::path& path) {
  LineReader reader(path);
  Trajectory trajectory;
  trajectory.name = path.string();
  while (reader.next()) {
    reader.expect_columns(kPoseColumns, kIndexedPoseColumns, "KITTI: [index] r11 r12 r13 tx ... tz");
    const auto& v = reader.values();
    const bool indexed = v.size() == kIndexedPoseColumns;
    const std::size_t first = indexed ? 1 : 0;
    Pose3 T_wc = Pose3::Identity();
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 4; ++col) T_wc.matrix()(row, col) = v[first + 4 * row + col];
    }
    std::int64_t frame_id = static_cast<std::int64_t>(trajectory.size());
    if (indexed) {
      frame_id = static_cast<std::int64_t>(v[0]);
      if (static_cast<double>(frame_id) != v[0] || frame_id < 0) {
        reader.fail("expected a non-negative integer frame index in column 1");
      }
      if (!trajectory.empty() && frame_id <= trajectory.frame_ids.back()) {
        reader.fail("frame index " + std::to_string(frame_id) + " does not increase");
      }
    }
    trajectory.push_back(T_wc, frame_id);
  }
  return trajectory;
}

void write_kitti(const std::filesystem::path& path, const Trajectory& trajectory) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  // The index column is only needed when frames are missing; plain 12 columns otherwise, which
  // every KITTI tool reads.
  const bool indexed = !ids_are_line_order(trajectory);
  char number[64];
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    if (indexed) out << trajectory.frame_ids[i] << ' ';
    const auto& M = trajectory.poses_wc[i].matrix();
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 4; ++col) {
        std::snprintf(number, sizeof number, "%.17g", M(row, col));
        out << number << (row == 2 && col == 3 ? '\n' : ' ');
      }
    }
  }
  if (!out) throw std::runtime_error("error writing " + path.string());
}

}  // namespace heslam::eval

// TUM RGB-D trajectory format: "stamp_s x y z qx qy qz qw" per line; heslam's own output format.
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "tools/eval/line_reader.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::eval {

namespace {
constexpr std::size_t kTumColumns = 8;
}  // namespace

Trajectory read_tum(const std::filesystem::path& path) {
  LineReader reader(path);
  Trajectory trajectory;
  trajectory.name = path.string();
  std::int64_t frame_id = 0;
  while (reader.next()) {
    reader.expect_columns(kTumColumns, 0, "TUM: stamp x y z qx qy qz qw");
    const auto& v = reader.values();
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (q.norm() < 1e-9) reader.fail("quaternion has zero norm");
    trajectory.push_back(make_pose({v[1], v[2], v[3]}, q), frame_id++, v[0]);
  }
  trajectory.frame = pose_frame_from_header(reader.header_comments());
  return trajectory;
}

void write_tum(const std::filesystem::path& path, const Trajectory& trajectory) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  // The pose's name says its frame: T_wb for body poses (the recorder's default), T_wc for a camera's.
  const bool body = trajectory.frame && *trajectory.frame == PoseFrame::body;
  out << "# timestamp tx ty tz qx qy qz qw (" << (body ? "T_wb" : "T_wc") << ", heslam)\n";
  if (trajectory.frame) out << pose_frame_header(*trajectory.frame) << "\n";
  char line[512];
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const Pose3& T = trajectory.poses_wc[i];
    const Eigen::Quaterniond q(Eigen::Matrix3d(T.linear()));
    const Eigen::Vector3d t = T.translation();
    // Stamps fall back to the frame id so that a stamp-less trajectory still writes valid TUM.
    const double stamp_s =
        trajectory.has_stamps() ? trajectory.stamps_s[i] : static_cast<double>(trajectory.frame_ids[i]);
    std::snprintf(line, sizeof line, "%.9f %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", stamp_s, t.x(), t.y(), t.z(),
                  q.x(), q.y(), q.z(), q.w());
    out << line;
  }
  if (!out) throw std::runtime_error("error writing " + path.string());
}

}  // namespace heslam::eval

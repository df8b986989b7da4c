// EuRoC MAV ground-truth csv (body frame): 8 columns "stamp_ns, p xyz, q wxyz" or the 17-column
// state_groundtruth_estimate0 layout that adds velocity and IMU biases (ignored here).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include <Eigen/Geometry>

#include "tools/eval/line_reader.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::eval {

namespace {
constexpr std::size_t kPoseColumns = 8;
constexpr std::size_t kStateColumns = 17;
constexpr double kSecondsPerNanosecond = 1e-9;
}  // namespace

Trajectory read_euroc(const std::filesystem::path& path) {
  LineReader reader(path);
  Trajectory trajectory;
  trajectory.name = path.string();
  std::int64_t frame_id = 0;
  while (reader.next()) {
    reader.expect_columns(kPoseColumns, kStateColumns, "EuRoC: stamp_ns, x y z, qw qx qy qz[, ...]");
    const auto& v = reader.values();
    // Nanosecond stamps need 61 bits: parse the token as an integer, not through a double.
    const long long stamp_ns = reader.integer_token(0);
    const Eigen::Quaterniond q(v[4], v[5], v[6], v[7]);
    if (q.norm() < 1e-9) reader.fail("quaternion has zero norm");
    trajectory.push_back(make_pose({v[1], v[2], v[3]}, q), frame_id++,
                         static_cast<double>(stamp_ns) * kSecondsPerNanosecond);
  }
  trajectory.frame = pose_frame_from_header(reader.header_comments());
  return trajectory;
}

void write_euroc(const std::filesystem::path& path, const Trajectory& trajectory) {
  if (!trajectory.has_stamps()) {
    throw std::runtime_error("cannot write " + path.string() + ": EuRoC csv needs time stamps");
  }
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  out << "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],"
         "q_RS_z []\n";
  if (trajectory.frame) out << pose_frame_header(*trajectory.frame) << "\n";
  char line[512];
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const Pose3& T = trajectory.poses_wc[i];
    const Eigen::Quaterniond q(Eigen::Matrix3d(T.linear()));
    const Eigen::Vector3d t = T.translation();
    const long long stamp_ns = std::llround(trajectory.stamps_s[i] / kSecondsPerNanosecond);
    std::snprintf(line, sizeof line, "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", stamp_ns, t.x(), t.y(), t.z(),
                  q.w(), q.x(), q.y(), q.z());
    out << line;
  }
  if (!out) throw std::runtime_error("error writing " + path.string());
}

}  // namespace heslam::eval

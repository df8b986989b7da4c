// The trajectory value every evaluation step passes around: poses T_wc with optional time stamps
// and KITTI-style frame ids.
//
// API:
//   Trajectory t;                       poses_wc[i] is the pose of sample i (camera to world)
//   t.has_stamps()                      false for KITTI files read without --times
//   t.subset(indices)                   the samples at `indices`, in that order
//   t.path_length_m()                   sum of distances between consecutive positions
//   apply_sim3(t, alignment)            left-multiplies every pose by a similarity transform
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "components/core/geometry/pose.hpp"
#include "tools/eval/pose_frame.hpp"

namespace heslam::eval {

// A similarity transform x -> scale * R * x + t. scale == 1 for rigid alignments.
struct Sim3 {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double scale = 1.0;
};

struct Trajectory {
  // Pose matrices are kept as read (KITTI files carry rotations orthonormal only to ~1e-7); Pose3's
  // inverse() uses the transposed rotation, exactly as evo's se3_inverse does.
  std::vector<Pose3> poses_wc;
  // Seconds; empty when the source has no time (KITTI pose files without a times file).
  std::vector<double> stamps_s;
  // Frame index of each pose: the leading KITTI index when present, else the line order (0, 1, ...).
  std::vector<std::int64_t> frame_ids;
  // Where the trajectory came from, for messages ("gt", a path, ...).
  std::string name;
  // The frame the poses are of, from / into the `# heslam frame:` header of TUM and EuRoC files;
  // unset: not known (files of other tools, KITTI files).
  std::optional<PoseFrame> frame;

  std::size_t size() const { return poses_wc.size(); }
  bool empty() const { return poses_wc.empty(); }
  bool has_stamps() const { return !stamps_s.empty(); }

  Eigen::Vector3d position_m(std::size_t i) const { return poses_wc[i].translation(); }
  double path_length_m() const;

  // Appends one sample. Readers use one overload per file, so stamps stay all-or-nothing.
  void push_back(const Pose3& T_wc, std::int64_t frame_id);
  void push_back(const Pose3& T_wc, std::int64_t frame_id, double stamp_s);

  Trajectory subset(std::span<const std::size_t> indices) const;
};

// Left-multiplies every pose by `S`: R_new = R * R_wc, t_new = scale * R * t_wc + t (evo's
// scale-then-transform order).
void apply_sim3(Trajectory& trajectory, const Sim3& S);

// A rotation matrix and translation as a pose; `q` need not be normalised (it is normalised here).
Pose3 make_pose(const Eigen::Vector3d& t, const Eigen::Quaterniond& q);

}  // namespace heslam::eval

// Trajectory helpers: path length, subsets, similarity transforms.
#include "tools/eval/trajectory.hpp"

#include <Eigen/Geometry>

namespace heslam::eval {

double Trajectory::path_length_m() const {
  double length_m = 0.0;
  for (std::size_t i = 1; i < size(); ++i) length_m += (position_m(i) - position_m(i - 1)).norm();
  return length_m;
}

void Trajectory::push_back(const Pose3& T_wc, std::int64_t frame_id) {
  poses_wc.push_back(T_wc);
  frame_ids.push_back(frame_id);
}

void Trajectory::push_back(const Pose3& T_wc, std::int64_t frame_id, double stamp_s) {
  push_back(T_wc, frame_id);
  stamps_s.push_back(stamp_s);
}

Trajectory Trajectory::subset(std::span<const std::size_t> indices) const {
  Trajectory out;
  out.name = name;
  out.frame = frame;
  out.poses_wc.reserve(indices.size());
  out.frame_ids.reserve(indices.size());
  for (const std::size_t i : indices) {
    out.poses_wc.push_back(poses_wc[i]);
    out.frame_ids.push_back(frame_ids[i]);
    if (has_stamps()) out.stamps_s.push_back(stamps_s[i]);
  }
  return out;
}

void apply_sim3(Trajectory& trajectory, const Sim3& S) {
  for (Pose3& T_wc : trajectory.poses_wc) {
    const Eigen::Vector3d t_new = S.scale * (S.R * T_wc.translation()) + S.t;
    T_wc.linear() = (S.R * T_wc.linear()).eval();
    T_wc.translation() = t_new;
  }
}

Pose3 make_pose(const Eigen::Vector3d& t, const Eigen::Quaterniond& q) {
  Pose3 T = Pose3::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = t;
  return T;
}

}  // namespace heslam::eval

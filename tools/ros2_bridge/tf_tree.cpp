// REP 105 transforms from heslam's poses (see tf_tree.hpp).
#include "tools/ros2_bridge/tf_tree.hpp"

#include <stdexcept>

#include <Eigen/Geometry>

namespace heslam::ros2 {

Rep105Transforms rep105_transforms(const Pose3& T_wc, const Pose3& T_oc, const Pose3& T_B_rect, const Pose3& T_map_b0) {
  const Pose3 T_rect_B = T_B_rect.inverse();
  Rep105Transforms out;
  out.T_odom_base = T_B_rect * T_oc * T_rect_B;
  out.T_map_odom = T_map_b0 * T_B_rect * (T_wc * T_oc.inverse()) * T_rect_B;
  return out;
}

Pose3 gravity_aligned_map(const Eigen::Vector3d& g_w, const Pose3& T_B_rect) {
  if (!g_w.allFinite() || !(g_w.norm() > 0.0)) {
    throw std::invalid_argument("gravity_aligned_map: gravity must be finite and non-zero");
  }
  const Eigen::Vector3d g_b0 = T_B_rect.linear() * g_w;
  // The smallest rotation taking gravity's direction to -z (as the recorder's gravity_alignment).
  Pose3 T_map_b0 = Pose3::Identity();
  T_map_b0.linear() =
      Eigen::Quaterniond::FromTwoVectors(g_b0.normalized(), -Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T_map_b0;
}

}  // namespace heslam::ros2

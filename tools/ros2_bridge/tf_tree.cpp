// REP 105 transforms from heslam's poses (see tf_tree.hpp).
#include "tools/ros2_bridge/tf_tree.hpp"

namespace heslam::ros2 {

Rep105Transforms rep105_transforms(const Pose3& T_wc, const Pose3& T_oc, const Pose3& T_B_rect) {
  const Pose3 T_rect_B = T_B_rect.inverse();
  Rep105Transforms out;
  out.T_odom_base = T_B_rect * T_oc * T_rect_B;
  out.T_map_odom = T_B_rect * (T_wc * T_oc.inverse()) * T_rect_B;
  return out;
}

}  // namespace heslam::ros2

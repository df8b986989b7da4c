// msg::Pose <-> Pose3 (see pose.hpp).
#include "components/messages/pose.hpp"

namespace heslam::messages {

msg::Pose to_message(const Pose3& T_ab) {
  msg::Pose pose{};
  const Eigen::Vector3d t = T_ab.translation();
  const Eigen::Quaterniond q(Eigen::Matrix3d(T_ab.linear()));
  for (int i = 0; i < 3; ++i) pose.position_m[i] = t[i];
  pose.orientation_xyzw[0] = q.x();
  pose.orientation_xyzw[1] = q.y();
  pose.orientation_xyzw[2] = q.z();
  pose.orientation_xyzw[3] = q.w();
  return pose;
}

Pose3 to_pose(const msg::Pose& pose) {
  Eigen::Quaterniond q(pose.orientation_xyzw[3], pose.orientation_xyzw[0], pose.orientation_xyzw[1],
                       pose.orientation_xyzw[2]);
  const double norm = q.norm();
  if (!(norm > 0.0))
    q = Eigen::Quaterniond::Identity();  // an all-zero pose is "no pose": identity
  else
    q.coeffs() /= norm;
  Pose3 T = Pose3::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Vector3d(pose.position_m[0], pose.position_m[1], pose.position_m[2]);
  return T;
}

}  // namespace heslam::messages

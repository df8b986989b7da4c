// Helpers shared by the tests of loop corrections applied by the local mapper (the mapper's late
// keyframes, the loop closer's map copy): a mapper that only inserts, and a rigid motion.
#pragma once

#include <Eigen/Geometry>

#include "components/core/geometry/pose.hpp"
#include "components/core/mapping/local_mapper.hpp"

namespace heslam::test {

// Every stage that would move a pose or a point after insertion is off: poses change only through
// the corrections under test, so they can be checked to the last bit.
inline LocalMapperOptions insertion_only() {
  LocalMapperOptions options;
  options.enable_triangulation = false;
  options.enable_fusion = false;
  options.enable_bundle_adjustment = false;
  options.enable_keyframe_culling = false;
  return options;
}

// A rotation of angle_rad about axis followed by a translation t.
inline Pose3 motion(double angle_rad, const Eigen::Vector3d& axis, const Eigen::Vector3d& t) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

}  // namespace heslam::test

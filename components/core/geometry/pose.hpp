// Rigid-body pose type and naming convention shared by the whole core library.
//
// A pose T_ab is a rigid transform that maps coordinates of a point in frame b to frame a:
//   p_a = T_ab * p_b.  T_wc is "camera to world" (the camera's pose in the world),
//   T_cw = T_wc.inverse() projects world points into the camera.
#pragma once

#include <Eigen/Geometry>

namespace heslam {

using Pose3 = Eigen::Isometry3d;

}  // namespace heslam

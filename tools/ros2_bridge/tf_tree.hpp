// REP 105 frames from heslam's poses: map -> odom -> base_link on /tf, base_link -> camera and
// map -> heslam's world on /tf_static. DDS-free, so the composition is unit-tested on known poses.
//
// heslam tracks the rectified left camera (c) with the world (w) at that camera's first keyframe. The
// body frame (base_link, b) is the calibration's (EuRoC T_BS; the identity when it has none), related to
// the rectified camera by T_B_rect (StereoRectifier::T_B_rect, as the recorder's body poses). As the
// recorder's body trajectory, map is the body at the first keyframe: T_map_x = T_B_rect T_w_x T_B_rect^-1.
// Odometry.T_oc is the camera in odom (T_wc without the loop corrections the frontend followed), so
// odom -> base_link never jumps at a correction and map -> odom carries the corrections.
//
// Inertial runs (docs/imu.md, Gravity-aligned outputs): once the odometry carries gravity (g_w, in the
// world), map is the gravity-aligned frame instead: the body at the first keyframe turned by the
// smallest rotation that makes its z point up (T_map_b0, a pure rotation: the same origin, no rotation
// about the vertical added), as the recorder's files (tools/recorder, gravity_alignment). odom stays
// the body at the first keyframe, so odom -> base_link stays continuous and map -> odom takes the turn.
#pragma once

#include "components/core/geometry/pose.hpp"

namespace heslam::ros2 {

struct Rep105Transforms {
  Pose3 T_map_odom = Pose3::Identity();   // odom -> map: the loop corrections (constant between them)
  Pose3 T_odom_base = Pose3::Identity();  // base_link -> odom: continuous
};

// The dynamic transforms of one tracked frame;
// T_map_odom * T_odom_base = T_map_b0 T_B_rect T_wc T_B_rect^-1 (T_map_b0: the identity without gravity).
Rep105Transforms rep105_transforms(const Pose3& T_wc, const Pose3& T_oc, const Pose3& T_B_rect,
                                   const Pose3& T_map_b0 = Pose3::Identity());

// The gravity-aligned map from the body at the first keyframe (b0), given gravity in heslam's world
// (Odometry.g_w, any length, not zero): z of map is -gravity, the rotation the smallest that does it.
Pose3 gravity_aligned_map(const Eigen::Vector3d& g_w, const Pose3& T_B_rect);

// The static ones: base_link -> camera is T_B_rect; heslam's world frame (the frame_id of the odometry,
// pose, path and cloud topics) sits in map at T_map_world = T_map_b0 T_B_rect.
inline Pose3 base_to_camera(const Pose3& T_B_rect) { return T_B_rect; }
inline Pose3 map_to_world(const Pose3& T_B_rect, const Pose3& T_map_b0 = Pose3::Identity()) {
  return T_map_b0 * T_B_rect;
}

}  // namespace heslam::ros2

// The IMU input of the loop closer's global bundle adjustment in an inertial run (issue 34): the map's
// keyframes in time order, per map, the IMU readings between consecutive ones preintegrated, and a
// first guess of every chain keyframe's velocity and biases.
//
// Neither the map nor the correction carries velocities or biases (the mapper's inertial local BA is off
// by default, and keeps its states to itself), so the guess is made here from the poses:
//   - the gyroscope bias from the keyframes' rotations against the preintegrated ones
//     (estimate_gyro_bias, over every interval of the map), then the intervals preintegrated again
//     around it, so the BA's first-order bias correction starts close;
//   - the accelerometer bias zero (the BA's prior holds it near zero, within 0.2 m/s^2 by default);
//   - the velocity at keyframe i from the positions of i and j and the interval's preintegrated position
//     (p_j = p_i + v_i t + g t^2 / 2 + R_i dp), at a chain's last keyframe from its predecessor's
//     velocity (v_j = v_i + g t + R_i dv): exact on exact data.
// An interval the buffer cannot give (readings discarded, a gap, the IMU not yet there) or longer than
// max_interval_s breaks the chain there; the report counts why.
#pragma once

#include <cstdint>
#include <string>

#include "components/core/geometry/pose.hpp"
#include "components/core/imu/imu_buffer.hpp"
#include "components/core/loop/global_bundle_adjustment.hpp"
#include "components/core/map/map.hpp"

namespace heslam {

struct GlobalInertialChainOptions {
  // Two keyframes further apart than this get no IMU factor (the preintegration's first-order bias
  // correction and its covariance are meant for keyframe intervals, ORB-SLAM3 keeps them under ~0.5 s
  // but culling makes longer ones).
  double max_interval_s = 3.0;
};

struct GlobalInertialChainReport {
  int intervals = 0;    // in the input
  int not_covered = 0;  // consecutive keyframes the buffer cannot give the IMU between
  int too_long = 0;     // over max_interval_s
  bool gyro_bias_estimated = false;
  Eigen::Vector3d gyro_bias_rad_s = Eigen::Vector3d::Zero();
  std::string first_problem;  // the first interval left out and why (one line), else empty
};

// The input for GlobalBundleAdjustment::compute over `map`'s live keyframes. Camera stamps turn into IMU
// stamps with time_offset_ns (ImuCalibration: t_imu = t_camera + offset). T_cb: IMU body -> rectified left
// camera (InertialMapping's T_cb = T_B_rect^-1 T_BS).
GlobalInertialInput build_global_inertial_input(const Map& map, const ImuBuffer& buffer, const Pose3& T_cb,
                                                std::int64_t time_offset_ns, const ImuNoise& noise,
                                                const Eigen::Vector3d& gravity_w,
                                                const GlobalInertialChainOptions& options = {},
                                                GlobalInertialChainReport* report = nullptr);

}  // namespace heslam

// Smooth, seeded camera-rig trajectories: a C2 cubic B-spline through jittered control points,
// travelled at a realistic speed, heading along the path with smooth seeded oscillations.
//
// The body frame B is x forward, y left, z up (a vehicle / drone convention); the world is z up.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "components/core/geometry/pose.hpp"
#include "tools/synth/preset.hpp"

namespace heslam::synth {

// The nominal path of a scene: control points (world, metres) and whether it closes on itself.
struct PathSpec {
  std::vector<Eigen::Vector3d> control_points_w;
  bool closed = true;
};

class Trajectory {
 public:
  // smooth (heslam-synth --imu): the motion is C2 in time so that an IMU's readings are defined
  // everywhere. The spline parameter then runs proportional to the distance (not through the
  // piecewise-linear arc-length table, whose kinks make the acceleration a sum of impulses), so the
  // speed varies a little with the control points' spacing, and each speed change follows a
  // smoothstep instead of a constant acceleration (same durations and distances, continuous
  // acceleration). Default false: the motion every existing render was made with, byte for byte.
  Trajectory(const PathSpec& path, const TrajectorySpec& spec, std::uint64_t seed, bool smooth = false);

  Pose3 T_wb(double t_s) const;
  Eigen::Vector3d velocity_w(double t_s) const;  // m/s, world frame (smooth: exact)
  // Smooth trajectories only (throw otherwise): the exact acceleration in the world, and the body's
  // angular velocity in the body frame (a Richardson-extrapolated central difference, ~1e-9 rad/s).
  Eigen::Vector3d acceleration_w(double t_s) const;
  Eigen::Vector3d angular_velocity_b(double t_s) const;
  bool smooth() const { return smooth_; }
  double length_m() const { return arc_length_.back(); }

 private:
  // Travelled distance and its first two time derivatives.
  struct Travel {
    double s_m = 0.0;
    double speed_mps = 0.0;
    double accel_mps2 = 0.0;
  };
  Travel smooth_travel_at(double t_s) const;
  Eigen::Vector3d spline_derivative(double u, int order) const;  // d^order P / du^order, order 1 or 2
  Eigen::Vector3d spline_point(double u) const;                  // u in [0, num_segments)
  double distance_at(double t_s) const;                          // travelled arc length at time t
  double param_at_distance(double s_m) const;
  Eigen::Vector3d position_at_distance(double s_m) const { return spline_point(param_at_distance(s_m)); }

  std::vector<Eigen::Vector3d> points_;  // jittered control points (padded for open paths)
  bool closed_ = true;
  int num_segments_ = 0;
  TrajectorySpec spec_;
  // Speed profile with stops: from t0_s on, s = s0_m + v0 dt + a dt^2 / 2. Empty: the constant
  // speed profile (accelerate over accel_time_s, then cruise).
  struct SpeedPhase {
    double t0_s = 0.0;
    double s0_m = 0.0;
    double v0_mps = 0.0;
    double a_mps2 = 0.0;
    double duration_s = 0.0;  // of an accelerating phase (its successor's start minus its own)
  };
  void plan_stops();

  bool smooth_ = false;
  std::vector<SpeedPhase> speed_phases_;
  std::vector<double> arc_length_;  // cumulative length at each table sample
  double table_step_u_ = 0.0;
  double phases_[6] = {0, 0, 0, 0, 0, 0};
};

}  // namespace heslam::synth

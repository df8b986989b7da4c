// Body motions with closed-form poses, their exact IMU readings (gravity tilted in the visual world as a
// stereo camera's first frame would have it, a constant bias, optional white noise and bias random walk)
// and the visual-inertial initializer's input built from them: known answers for the inertial tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "components/core/imu/inertial_initialization.hpp"
#include "components/core/imu/preintegration.hpp"
#include "components/core/imu/so3.hpp"

namespace heslam::test {

// Position, velocity, acceleration and rotation of the body in the visual world w at time t (s).
struct Motion {
  std::function<Eigen::Vector3d(double)> position, velocity, acceleration;
  std::function<Eigen::Matrix3d(double)> rotation;

  // w_b = (R^T dR/dt)^vee by a central difference (error ~1e-10 rad/s).
  Eigen::Vector3d angular_velocity(double t) const {
    constexpr double h = 1e-5;
    const Eigen::Matrix3d W = rotation(t).transpose() * (rotation(t + h) - rotation(t - h)) / (2.0 * h);
    return {0.5 * (W(2, 1) - W(1, 2)), 0.5 * (W(0, 2) - W(2, 0)), 0.5 * (W(1, 0) - W(0, 1))};
  }
  NavState state(double t) const { return {rotation(t), position(t), velocity(t)}; }
  Pose3 pose(double t) const {
    Pose3 T = Pose3::Identity();
    T.linear() = rotation(t);
    T.translation() = position(t);
    return T;
  }
};

// Hand-held-like: half a metre of swaying with 20-40 degrees of rotation about every axis within 2 s.
inline Motion ordinary_motion() {
  Motion m;
  m.position = [](double t) {
    return Eigen::Vector3d(0.3 * std::sin(1.7 * t), 0.2 * std::cos(2.3 * t) + 0.1 * t, 0.15 * std::sin(3.1 * t + 0.4));
  };
  m.velocity = [](double t) {
    return Eigen::Vector3d(0.51 * std::cos(1.7 * t), -0.46 * std::sin(2.3 * t) + 0.1, 0.465 * std::cos(3.1 * t + 0.4));
  };
  m.acceleration = [](double t) {
    return Eigen::Vector3d(-0.867 * std::sin(1.7 * t), -1.058 * std::cos(2.3 * t), -1.4415 * std::sin(3.1 * t + 0.4));
  };
  m.rotation = [](double t) {
    return so3::exp(Eigen::Vector3d(0.4 * std::sin(1.3 * t), 0.35 * std::sin(1.9 * t + 1.0), 0.5 * std::sin(0.8 * t)));
  };
  return m;
}

// At rest, or moving at a constant velocity, without rotation (what a tripod or a cart gives).
inline Motion uniform_motion(const Eigen::Vector3d& velocity) {
  const Eigen::Matrix3d R = so3::exp(Eigen::Vector3d(0.1, -0.2, 0.3));
  Motion m;
  // Component-wise: GCC 12 warns of an uninitialized read in the Eigen expression inside std::function.
  const double vx = velocity.x(), vy = velocity.y(), vz = velocity.z();
  m.position = [=](double t) { return Eigen::Vector3d(1.0 + vx * t, 2.0 + vy * t, 0.5 + vz * t); };
  m.velocity = [=](double) { return Eigen::Vector3d(vx, vy, vz); };
  m.acceleration = [](double) { return Eigen::Vector3d::Zero(); };
  m.rotation = [R](double) { return R; };
  return m;
}

struct SyntheticImu {
  // The visual world's orientation against gravity: the first camera frame is tilted.
  Eigen::Matrix3d R_wg = so3::exp(Eigen::Vector3d(0.35, -0.6, 0.2));
  double gravity_m_s2 = 9.81;
  double rate_hz = 200.0;
  ImuBias bias;        // at t = 0
  bool noisy = false;  // white noise and bias random walk of `noise`
  ImuNoise noise;      // also the model the preintegration carries
  std::uint64_t seed = 1;

  Eigen::Vector3d gravity_w() const { return R_wg * Eigen::Vector3d(0.0, 0.0, -gravity_m_s2); }

  // Readings over [t0, t1]; true_bias receives the bias at each reading.
  std::vector<ImuSample> samples(const Motion& motion, double t0, double t1,
                                 std::vector<ImuBias>* true_bias = nullptr) const {
    std::mt19937_64 random(seed);
    std::normal_distribution<double> unit(0.0, 1.0);
    const auto draw = [&] { return Eigen::Vector3d(unit(random), unit(random), unit(random)); };
    const double dt = 1.0 / rate_hz;
    ImuBias b = bias;
    std::vector<ImuSample> out;
    const int count = static_cast<int>(std::lround((t1 - t0) * rate_hz));
    for (int k = 0; k <= count; ++k) {
      const double t = t0 + k * dt;
      ImuSample s;
      s.stamp_ns = std::llround(t * 1e9);
      s.gyro_rad_s = motion.angular_velocity(t) + b.gyro_rad_s;
      s.accel_m_s2 = motion.rotation(t).transpose() * (motion.acceleration(t) - gravity_w()) + b.accel_m_s2;
      if (noisy) {
        s.gyro_rad_s += noise.gyro_noise_density / std::sqrt(dt) * draw();
        s.accel_m_s2 += noise.accel_noise_density / std::sqrt(dt) * draw();
      }
      out.push_back(s);
      if (true_bias) true_bias->push_back(b);
      if (noisy) {
        b.gyro_rad_s += noise.gyro_random_walk * std::sqrt(dt) * draw();
        b.accel_m_s2 += noise.accel_random_walk * std::sqrt(dt) * draw();
      }
    }
    return out;
  }
};

// Poses every keyframe_s over [t0, t0 + duration_s] (exact, or with isotropic noise of the given
// stddevs) and the intervals preintegrated around `linearization`.
inline InertialInitInput make_init_input(const Motion& motion, const std::vector<ImuSample>& samples, double t0,
                                         double duration_s, double keyframe_s, const ImuBias& linearization,
                                         const ImuNoise& noise, double pose_rotation_stddev_rad = 0.0,
                                         double pose_position_stddev_m = 0.0, std::uint64_t seed = 2) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const auto draw = [&] { return Eigen::Vector3d(unit(random), unit(random), unit(random)); };
  InertialInitInput input;
  const int count = static_cast<int>(std::lround(duration_s / keyframe_s));
  for (int k = 0; k <= count; ++k) {
    const double t = t0 + k * keyframe_s;
    Pose3 T = motion.pose(t);
    T.linear() = T.linear() * so3::exp(pose_rotation_stddev_rad * draw());
    T.translation() += pose_position_stddev_m * draw();
    input.T_wb.push_back(T);
    input.stamps_ns.push_back(std::llround(t * 1e9));
  }
  for (int k = 0; k < count; ++k) {
    input.intervals.push_back(preintegrate(samples, input.stamps_ns[k], input.stamps_ns[k + 1], linearization, noise));
  }
  return input;
}

// The angle between the estimated and the true direction of gravity, in degrees.
inline double gravity_error_deg(const InertialInitResult& result, const SyntheticImu& imu) {
  const Eigen::Vector3d estimated = result.R_wg * Eigen::Vector3d(0.0, 0.0, -1.0);
  const Eigen::Vector3d truth = imu.gravity_w().normalized();
  return std::atan2(estimated.cross(truth).norm(), estimated.dot(truth)) * 180.0 / M_PI;
}

}  // namespace heslam::test

// IMU preintegration on the manifold between two instants (frames or keyframes): the relative
// rotation, velocity and position increments of the body, their covariance and their Jacobians with
// respect to the gyroscope and accelerometer biases, so that a bias update corrects the increments at
// first order instead of integrating again (Forster et al., "On-Manifold Preintegration for Real-Time
// Visual-Inertial Odometry", T-RO 2017, sections V-VI; the order of updates is ORB-SLAM3's).
//
// Frames: the body frame b is the IMU's (EuRoC's T_BS of imu0 is the identity); measurements are the
// body's angular velocity w_b and specific force a_b = R_wb^T (acc_w - g_w). Noise densities are the
// continuous-time figures of a Kalibr / EuRoC sensor.yaml.
#pragma once

#include <cstdint>
#include <span>

#include <Eigen/Core>

namespace heslam {

// One IMU reading, as EuRoC's imu0/data.csv holds it.
struct ImuSample {
  std::int64_t stamp_ns = 0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

// Continuous-time noise model (sensor.yaml names). Defaults: the EuRoC VI sensor's ADIS16448.
struct ImuNoise {
  double gyro_noise_density = 1.6968e-4;  // rad/s/sqrt(Hz)    gyroscope_noise_density
  double gyro_random_walk = 1.9393e-5;    // rad/s^2/sqrt(Hz)  gyroscope_random_walk
  double accel_noise_density = 2.0e-3;    // m/s^2/sqrt(Hz)    accelerometer_noise_density
  double accel_random_walk = 3.0e-3;      // m/s^3/sqrt(Hz)    accelerometer_random_walk
};

struct ImuBias {
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();
};

// The body's state in the world frame.
struct NavState {
  Eigen::Matrix3d R_wb = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_wb = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_wb = Eigen::Vector3d::Zero();
};

// Covariance blocks are ordered rotation (3), velocity (3), position (3).
using Matrix9d = Eigen::Matrix<double, 9, 9>;

class ImuPreintegration {
 public:
  // Integrates around `bias` (the linearization point of the bias Jacobians).
  explicit ImuPreintegration(const ImuBias& bias = {}, const ImuNoise& noise = {});

  // Adds one measurement held constant over dt_s > 0 (the caller passes the mean of two consecutive
  // samples: see preintegrate()).
  void integrate(const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2, double dt_s);

  double duration_s() const { return duration_s_; }
  const ImuBias& bias() const { return bias_; }
  const ImuNoise& noise() const { return noise_; }

  // The increments at the linearization bias.
  const Eigen::Matrix3d& delta_R() const { return delta_R_; }
  const Eigen::Vector3d& delta_v() const { return delta_v_; }
  const Eigen::Vector3d& delta_p() const { return delta_p_; }
  // The increments for another bias, corrected at first order (Forster eq. 44).
  Eigen::Matrix3d delta_R(const ImuBias& bias) const;
  Eigen::Vector3d delta_v(const ImuBias& bias) const;
  Eigen::Vector3d delta_p(const ImuBias& bias) const;

  // Covariance of the increments' errors (rotation as a right perturbation) from measurement noise.
  const Matrix9d& covariance() const { return covariance_; }
  // Covariance of the bias change over the interval (gyro, then accel): the random walks times the duration.
  Eigen::Matrix<double, 6, 6> bias_random_walk_covariance() const;

  // Jacobians of the increments with respect to the biases.
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dv_dbg() const { return dv_dbg_; }
  const Eigen::Matrix3d& dv_dba() const { return dv_dba_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }
  const Eigen::Matrix3d& dp_dba() const { return dp_dba_; }

  // The state at the end from the state at the start, with gravity g_w (e.g. (0, 0, -9.81) in a
  // z-up world) and the given bias.
  NavState predict(const NavState& start, const Eigen::Vector3d& gravity_w, const ImuBias& bias) const;
  NavState predict(const NavState& start, const Eigen::Vector3d& gravity_w) const {
    return predict(start, gravity_w, bias_);
  }

 private:
  ImuBias bias_;
  ImuNoise noise_;
  double duration_s_ = 0.0;
  Eigen::Matrix3d delta_R_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d delta_v_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d delta_p_ = Eigen::Vector3d::Zero();
  Matrix9d covariance_ = Matrix9d::Zero();
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dba_ = Eigen::Matrix3d::Zero();
};

// The reading at stamp_ns between readings a and b (a.stamp_ns < b.stamp_ns), linear in time: how a
// frame stamp between two IMU stamps gets its reading.
ImuSample interpolate_imu(const ImuSample& a, const ImuSample& b, std::int64_t stamp_ns);

// Preintegrates the samples over [t0_ns, t1_ns]: each stretch between two consecutive samples with
// their mean; at t0 and t1 the samples are interpolated linearly, so frames between IMU stamps get
// exactly their interval. Samples must be in increasing stamp order and cover [t0_ns, t1_ns]; throws
// std::invalid_argument otherwise (naming the uncovered end).
ImuPreintegration preintegrate(std::span<const ImuSample> samples, std::int64_t t0_ns, std::int64_t t1_ns,
                               const ImuBias& bias = {}, const ImuNoise& noise = {});

}  // namespace heslam

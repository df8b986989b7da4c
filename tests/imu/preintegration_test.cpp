// IMU preintegration with known answers: SO(3) maps against their definitions, increments against an
// analytic trajectory sampled like a 200 Hz / 1 kHz IMU, the bias Jacobians against re-integration, and
// the propagated covariance against a Monte Carlo of noisy measurements.
#include "components/core/imu/preintegration.hpp"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/LU>

#include "components/core/imu/gyro_bias.hpp"
#include "components/core/imu/so3.hpp"

namespace heslam {
namespace {

const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);

double rotation_error_rad(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return so3::log(a.transpose() * b).norm();
}

TEST(So3, ExpAndLogAreInverseAndJacobiansMatchFiniteDifferences) {
  for (const Eigen::Vector3d& phi : {Eigen::Vector3d(0.3, -0.2, 0.9), Eigen::Vector3d(1e-7, 2e-7, -1e-7),
                                     Eigen::Vector3d(0.0, 0.0, M_PI - 1e-9), Eigen::Vector3d(2.0, 1.0, -0.5)}) {
    const Eigen::Matrix3d R = so3::exp(phi);
    EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    EXPECT_LT((so3::exp(so3::log(R)) - R).norm(), 1e-8) << phi.transpose();
    // Exp(phi + d) = Exp(phi) Exp(Jr d) and Log(Exp(phi) Exp(d)) = phi + Jr^-1 d, to first order in d.
    const Eigen::Vector3d d(1e-6, -2e-6, 1.5e-6);
    EXPECT_LT((so3::exp(phi + d) - R * so3::exp(so3::right_jacobian(phi) * d)).norm(), 1e-10);
    if (phi.norm() < 3.0) {
      EXPECT_LT((so3::log(R * so3::exp(d)) - (phi + so3::right_jacobian_inverse(phi) * d)).norm(), 1e-10);
    }
    EXPECT_LT((so3::right_jacobian(phi) * so3::right_jacobian_inverse(phi) - Eigen::Matrix3d::Identity()).norm(), 1e-9);
  }
  EXPECT_NEAR(so3::log(so3::exp(Eigen::Vector3d(0.0, M_PI, 0.0))).norm(), M_PI, 1e-9);
}

// A smooth body trajectory with closed-form position and orientation; the IMU's readings from it.
struct Trajectory {
  static Eigen::Vector3d position(double t) { return {std::sin(t), std::cos(1.3 * t), 0.5 * std::sin(0.7 * t)}; }
  static Eigen::Vector3d velocity(double t) {
    return {std::cos(t), -1.3 * std::sin(1.3 * t), 0.35 * std::cos(0.7 * t)};
  }
  static Eigen::Vector3d acceleration(double t) {
    return {-std::sin(t), -1.69 * std::cos(1.3 * t), -0.245 * std::sin(0.7 * t)};
  }
  static Eigen::Matrix3d rotation(double t) {
    return so3::exp(Eigen::Vector3d(0.3 * std::sin(t), 0.4 * t, 0.2 * std::cos(2.0 * t)));
  }
  // w_b = (R^T dR/dt)^vee, by a central difference (error ~1e-10 rad/s).
  static Eigen::Vector3d angular_velocity(double t) {
    constexpr double h = 1e-5;
    const Eigen::Matrix3d dR = (rotation(t + h) - rotation(t - h)) / (2.0 * h);
    const Eigen::Matrix3d W = rotation(t).transpose() * dR;
    return {0.5 * (W(2, 1) - W(1, 2)), 0.5 * (W(0, 2) - W(2, 0)), 0.5 * (W(1, 0) - W(0, 1))};
  }
  static ImuSample sample(double t) {
    ImuSample s;
    s.stamp_ns = std::llround(t * 1e9);
    s.gyro_rad_s = angular_velocity(t);
    s.accel_m_s2 = rotation(t).transpose() * (acceleration(t) - kGravity);
    return s;
  }
  static NavState state(double t) { return {rotation(t), position(t), velocity(t)}; }
  static std::vector<ImuSample> samples(double t0, double t1, double rate_hz) {
    std::vector<ImuSample> out;
    const int n = static_cast<int>(std::lround((t1 - t0) * rate_hz));
    for (int k = 0; k <= n; ++k) out.push_back(sample(t0 + k / rate_hz));
    return out;
  }
};

// The prediction from exact noise-free readings converges to the trajectory as the rate grows, at
// second order (5x the rate: 25x smaller errors).
TEST(ImuPreintegration, PredictsAnAnalyticTrajectoryAndConvergesWithTheRate) {
  const double t0 = 0.4;
  const double t1 = 1.4;
  double previous_position_error = 0.0;
  for (const double rate_hz : {200.0, 1000.0}) {
    const std::vector<ImuSample> samples = Trajectory::samples(t0 - 0.05, t1 + 0.05, rate_hz);
    const ImuPreintegration preintegration = preintegrate(samples, std::llround(t0 * 1e9), std::llround(t1 * 1e9));
    EXPECT_NEAR(preintegration.duration_s(), t1 - t0, 1e-9);
    const NavState predicted = preintegration.predict(Trajectory::state(t0), kGravity);
    const NavState truth = Trajectory::state(t1);
    const double position_error = (predicted.p_wb - truth.p_wb).norm();
    std::printf("[ figures  ] %.0f Hz over %.1f s: position %.2e m, velocity %.2e m/s, rotation %.2e rad\n", rate_hz,
                t1 - t0, position_error, (predicted.v_wb - truth.v_wb).norm(),
                rotation_error_rad(predicted.R_wb, truth.R_wb));
    EXPECT_LT(position_error, rate_hz == 200.0 ? 2e-5 : 1e-6);
    EXPECT_LT((predicted.v_wb - truth.v_wb).norm(), rate_hz == 200.0 ? 4e-5 : 2e-6);
    EXPECT_LT(rotation_error_rad(predicted.R_wb, truth.R_wb), rate_hz == 200.0 ? 1e-5 : 5e-7);
    if (previous_position_error > 0.0) {
      EXPECT_LT(position_error, previous_position_error / 10.0);
    }
    previous_position_error = position_error;
  }
}

// Frames between IMU stamps: [t0, t1] cut inside sample intervals equals the sum of its parts.
TEST(ImuPreintegration, IntervalsBetweenSampleStampsAreInterpolatedAndChain) {
  const std::vector<ImuSample> samples = Trajectory::samples(0.0, 1.0, 200.0);
  const std::int64_t t0 = 101'234'567;
  const std::int64_t tm = 503'000'001;
  const std::int64_t t1 = 897'654'321;
  const ImuPreintegration whole = preintegrate(samples, t0, t1);
  EXPECT_NEAR(whole.duration_s(), (t1 - t0) * 1e-9, 1e-12);
  const ImuPreintegration first = preintegrate(samples, t0, tm);
  const ImuPreintegration second = preintegrate(samples, tm, t1);
  const NavState start = Trajectory::state(t0 * 1e-9);
  const NavState via = second.predict(first.predict(start, kGravity), kGravity);
  const NavState direct = whole.predict(start, kGravity);
  EXPECT_LT((via.p_wb - direct.p_wb).norm(), 1e-5);
  EXPECT_LT(rotation_error_rad(via.R_wb, direct.R_wb), 1e-6);
  EXPECT_THROW(preintegrate(samples, -5, t1), std::invalid_argument);
  EXPECT_THROW(preintegrate(samples, t0, 2'000'000'000), std::invalid_argument);
  EXPECT_THROW(preintegrate(samples, t1, t0), std::invalid_argument);
}

// A bias change corrected with the Jacobians matches integrating again with that bias, to second order.
TEST(ImuPreintegration, BiasJacobiansMatchReintegration) {
  const std::vector<ImuSample> samples = Trajectory::samples(0.0, 1.2, 200.0);
  ImuBias linearization;
  linearization.gyro_rad_s = Eigen::Vector3d(0.01, -0.02, 0.005);
  linearization.accel_m_s2 = Eigen::Vector3d(0.05, 0.02, -0.1);
  const ImuPreintegration preintegration = preintegrate(samples, 100'000'000, 1'100'000'000, linearization);
  ImuBias updated = linearization;
  updated.gyro_rad_s += Eigen::Vector3d(2e-3, 1e-3, -3e-3);
  updated.accel_m_s2 += Eigen::Vector3d(-2e-2, 3e-2, 1e-2);
  const ImuPreintegration again = preintegrate(samples, 100'000'000, 1'100'000'000, updated);

  const double rotation_change = rotation_error_rad(preintegration.delta_R(), again.delta_R());
  const double velocity_change = (preintegration.delta_v() - again.delta_v()).norm();
  const double position_change = (preintegration.delta_p() - again.delta_p()).norm();
  const double rotation_left = rotation_error_rad(preintegration.delta_R(updated), again.delta_R());
  const double velocity_left = (preintegration.delta_v(updated) - again.delta_v()).norm();
  const double position_left = (preintegration.delta_p(updated) - again.delta_p()).norm();
  std::printf(
      "[ figures  ] bias change: rotation %.2e -> %.2e rad, velocity %.2e -> %.2e m/s, position %.2e -> "
      "%.2e m after the first-order correction\n",
      rotation_change, rotation_left, velocity_change, velocity_left, position_change, position_left);
  EXPECT_LT(rotation_left, 0.02 * rotation_change);
  EXPECT_LT(velocity_left, 0.02 * velocity_change);
  EXPECT_LT(position_left, 0.02 * position_change);
  EXPECT_LT((preintegration.delta_R(linearization) - preintegration.delta_R()).norm(), 1e-12);
}

// The propagated covariance is the spread of the increments over noisy measurements (Monte Carlo).
TEST(ImuPreintegration, CovarianceMatchesAMonteCarloOfNoisyMeasurements) {
  constexpr double kRateHz = 200.0;
  constexpr int kSteps = 100;  // 0.5 s
  constexpr int kRuns = 3000;
  ImuNoise noise;
  noise.gyro_noise_density = 2e-3;  // larger than the ADIS's so the spread dominates rounding
  noise.accel_noise_density = 2e-2;
  const double dt = 1.0 / kRateHz;
  std::vector<ImuSample> exact;
  for (int k = 0; k < kSteps; ++k) exact.push_back(Trajectory::sample(0.3 + k * dt));

  ImuPreintegration nominal(ImuBias{}, noise);
  for (const ImuSample& s : exact) nominal.integrate(s.gyro_rad_s, s.accel_m_s2, dt);

  std::mt19937_64 random(7);
  std::normal_distribution<double> unit(0.0, 1.0);
  const double gyro_sigma = noise.gyro_noise_density / std::sqrt(dt);
  const double accel_sigma = noise.accel_noise_density / std::sqrt(dt);
  Matrix9d sample_covariance = Matrix9d::Zero();
  for (int run = 0; run < kRuns; ++run) {
    ImuPreintegration noisy(ImuBias{}, noise);
    for (const ImuSample& s : exact) {
      const Eigen::Vector3d gyro_noise(unit(random), unit(random), unit(random));
      const Eigen::Vector3d accel_noise(unit(random), unit(random), unit(random));
      noisy.integrate(s.gyro_rad_s + gyro_sigma * gyro_noise, s.accel_m_s2 + accel_sigma * accel_noise, dt);
    }
    Eigen::Matrix<double, 9, 1> error;
    const Eigen::Vector3d rotation_error = so3::log(nominal.delta_R().transpose() * noisy.delta_R());
    const Eigen::Vector3d velocity_error = noisy.delta_v() - nominal.delta_v();
    const Eigen::Vector3d position_error = noisy.delta_p() - nominal.delta_p();
    for (int i = 0; i < 3; ++i) {
      error(i) = rotation_error(i);
      error(3 + i) = velocity_error(i);
      error(6 + i) = position_error(i);
    }
    sample_covariance += error * error.transpose() / kRuns;
  }
  const Matrix9d& propagated = nominal.covariance();
  for (int block = 0; block < 3; ++block) {
    const double expected = propagated.block<3, 3>(3 * block, 3 * block).trace();
    const double measured = sample_covariance.block<3, 3>(3 * block, 3 * block).trace();
    std::printf("[ figures  ] block %d: propagated trace %.3e, Monte Carlo %.3e\n", block, expected, measured);
    EXPECT_NEAR(measured / expected, 1.0, 0.1) << "block " << block;
  }
  const double cross = propagated.block<3, 3>(6, 3).trace();
  const double measured_cross = sample_covariance.block<3, 3>(6, 3).trace();
  EXPECT_NEAR(measured_cross / cross, 1.0, 0.15);
  EXPECT_NEAR(nominal.bias_random_walk_covariance()(0, 0), noise.gyro_random_walk * noise.gyro_random_walk * 0.5,
              1e-15);
}

// A gyro bias added to exact readings is recovered from the true rotations of a few intervals.
TEST(GyroBias, RecoversAKnownBiasFromTrueRotations) {
  const Eigen::Vector3d true_bias(0.01, -0.03, 0.08);
  std::vector<ImuSample> samples = Trajectory::samples(0.0, 3.0, 200.0);
  for (ImuSample& s : samples) s.gyro_rad_s += true_bias;
  std::vector<ImuPreintegration> intervals;
  std::vector<Eigen::Matrix3d> rotations;
  for (double t = 0.1; t + 0.5 < 3.0; t += 0.5) {
    intervals.push_back(preintegrate(samples, std::llround(t * 1e9), std::llround((t + 0.5) * 1e9)));
    rotations.push_back(Trajectory::rotation(t).transpose() * Trajectory::rotation(t + 0.5));
  }
  // From a zero bias the first-order correction of a 0.09 rad/s bias leaves a second-order error;
  // integrating again around the first estimate removes it.
  const GyroBiasEstimate first = estimate_gyro_bias(intervals, rotations);
  EXPECT_LT((first.gyro_rad_s - true_bias).norm(), 2e-4) << first.gyro_rad_s.transpose();
  ImuBias around;
  around.gyro_rad_s = first.gyro_rad_s;
  std::vector<ImuPreintegration> again;
  for (double t = 0.1; t + 0.5 < 3.0; t += 0.5) {
    again.push_back(preintegrate(samples, std::llround(t * 1e9), std::llround((t + 0.5) * 1e9), around));
  }
  const GyroBiasEstimate estimate = estimate_gyro_bias(again, rotations);
  EXPECT_LT((estimate.gyro_rad_s - true_bias).norm(), 1e-6) << estimate.gyro_rad_s.transpose();
  EXPECT_LT(estimate.rms_residual_rad, 5e-6);  // the 200 Hz integration's own rotation error
  EXPECT_THROW(estimate_gyro_bias(std::span(intervals).first(1), std::span(rotations).first(1)), std::invalid_argument);
}

}  // namespace
}  // namespace heslam

// The Ceres IMU factor and the IMU-only propagation on synthetic motions with known states: the residual
// vanishes on exact data, its autodiff Jacobians match numeric differences, the bias random walk is
// whitened by its covariance, and the propagated covariance matches Monte Carlo spreads.
#include "components/core/imu/imu_factor.hpp"

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/LU>

#include "components/core/imu/propagation.hpp"
#include "synthetic_motion.hpp"

namespace heslam {
namespace {

struct StateBlocks {
  double q[4], p[3], v[3], bg[3], ba[3];
};

StateBlocks blocks_of(const NavState& state, const ImuBias& bias) {
  StateBlocks b;
  const Eigen::Quaterniond q(state.R_wb);
  b.q[0] = q.x();
  b.q[1] = q.y();
  b.q[2] = q.z();
  b.q[3] = q.w();
  for (int k = 0; k < 3; ++k) {
    b.p[k] = state.p_wb[k];
    b.v[k] = state.v_wb[k];
    b.bg[k] = bias.gyro_rad_s[k];
    b.ba[k] = bias.accel_m_s2[k];
  }
  return b;
}

ImuBias some_bias() {
  ImuBias bias;
  bias.gyro_rad_s = Eigen::Vector3d(0.01, -0.02, 0.015);
  bias.accel_m_s2 = Eigen::Vector3d(0.1, 0.05, -0.12);
  return bias;
}

// Exact readings with a bias, preintegrated around that bias: at the true states the residual is the
// 200 Hz integration's error only, and the factor whitens imu_residual() with the sqrt information.
TEST(ImuFactor, ResidualIsZeroOnExactDataAndWhitensTheUnweightedResidual) {
  const test::Motion motion = test::ordinary_motion();
  test::SyntheticImu imu;
  imu.bias = some_bias();
  const std::vector<ImuSample> samples = imu.samples(motion, 0.0, 1.5);
  const double ti = 0.4;
  const double tj = 0.9;
  const ImuPreintegration interval =
      preintegrate(samples, std::llround(ti * 1e9), std::llround(tj * 1e9), imu.bias, imu.noise);
  const NavState i = motion.state(ti);
  const NavState j = motion.state(tj);
  const Eigen::Matrix<double, 9, 1> r = imu_residual(interval, i, imu.bias, j, imu.gravity_w());
  std::printf("[ figures  ] exact data over 0.5 s: |r_R| %.2e rad, |r_v| %.2e m/s, |r_p| %.2e m\n", r.head<3>().norm(),
              r.segment<3>(3).norm(), r.tail<3>().norm());
  // The 200 Hz integration's own error (preintegration_test: ~1e-5 over 1 s), far below the noise: the
  // whitened residual is a few hundredths.
  EXPECT_LT(r.head<3>().norm(), 5e-6);
  EXPECT_LT(r.segment<3>(3).norm(), 4e-5);
  EXPECT_LT(r.tail<3>().norm(), 2e-5);
  EXPECT_LT((ImuIntervalResidual(interval).sqrt_information() * r).norm(), 0.1);

  std::unique_ptr<ceres::CostFunction> cost(ImuFactor::create(interval, imu.gravity_w()));
  ASSERT_EQ(cost->num_residuals(), 9);
  StateBlocks bi = blocks_of(i, imu.bias);
  StateBlocks bj = blocks_of(j, imu.bias);
  // Away from the truth, where the residual is large and the whitening shows.
  bj.v[0] += 0.05;
  bj.p[2] -= 0.02;
  bi.bg[1] += 0.003;
  const double* parameters[] = {bi.q, bi.p, bi.v, bi.bg, bi.ba, bj.q, bj.p, bj.v};
  Eigen::Matrix<double, 9, 1> whitened;
  ASSERT_TRUE(cost->Evaluate(parameters, whitened.data(), nullptr));
  NavState j_moved = j;
  j_moved.v_wb.x() += 0.05;
  j_moved.p_wb.z() -= 0.02;
  ImuBias bias_moved = imu.bias;
  bias_moved.gyro_rad_s.y() += 0.003;
  const ImuIntervalResidual weights(interval);
  const Eigen::Matrix<double, 9, 1> expected =
      weights.sqrt_information() * imu_residual(interval, i, bias_moved, j_moved, imu.gravity_w());
  EXPECT_LT((whitened - expected).norm(), 1e-7 * expected.norm()) << whitened.transpose() << "\n"
                                                                  << expected.transpose();
  // L^T L is the information.
  const Matrix9d information = weights.sqrt_information().transpose() * weights.sqrt_information();
  EXPECT_LT((information * interval.covariance() - Matrix9d::Identity()).norm(), 1e-6);
}

// Autodiff Jacobians against central differences in every parameter block (the quaternion's 4 ambient
// coordinates; the factor normalizes, so any direction is valid).
TEST(ImuFactor, JacobiansMatchNumericDifferences) {
  const test::Motion motion = test::ordinary_motion();
  test::SyntheticImu imu;
  const std::vector<ImuSample> samples = imu.samples(motion, 0.0, 1.5);
  const ImuPreintegration interval = preintegrate(samples, 300'000'000, 700'000'000, some_bias(), imu.noise);
  ImuBias bias = some_bias();
  bias.gyro_rad_s += Eigen::Vector3d(0.002, -0.001, 0.003);
  bias.accel_m_s2 += Eigen::Vector3d(-0.02, 0.03, 0.01);
  StateBlocks bi = blocks_of(motion.state(0.3), bias);
  StateBlocks bj = blocks_of(motion.state(0.7), bias);
  bj.p[0] += 0.01;
  bj.v[1] -= 0.03;
  std::unique_ptr<ceres::CostFunction> cost(ImuFactor::create(interval, imu.gravity_w()));
  double* parameters[] = {bi.q, bi.p, bi.v, bi.bg, bi.ba, bj.q, bj.p, bj.v};
  const int sizes[] = {4, 3, 3, 3, 3, 4, 3, 3};
  std::vector<std::vector<double>> analytic(8);
  std::vector<double*> jacobians(8);
  for (int b = 0; b < 8; ++b) {
    analytic[b].resize(9 * sizes[b]);
    jacobians[b] = analytic[b].data();
  }
  Eigen::Matrix<double, 9, 1> r0;
  ASSERT_TRUE(cost->Evaluate(parameters, r0.data(), jacobians.data()));
  double worst = 0.0;
  for (int b = 0; b < 8; ++b) {
    for (int c = 0; c < sizes[b]; ++c) {
      const double h = 1e-6;
      const double saved = parameters[b][c];
      Eigen::Matrix<double, 9, 1> plus, minus;
      parameters[b][c] = saved + h;
      cost->Evaluate(parameters, plus.data(), nullptr);
      parameters[b][c] = saved - h;
      cost->Evaluate(parameters, minus.data(), nullptr);
      parameters[b][c] = saved;
      const Eigen::Matrix<double, 9, 1> numeric = (plus - minus) / (2.0 * h);
      Eigen::Matrix<double, 9, 1> column;
      for (int row = 0; row < 9; ++row) column[row] = analytic[b][row * sizes[b] + c];
      const double error = (numeric - column).norm() / std::max(1.0, column.norm());
      worst = std::max(worst, error);
      EXPECT_LT(error, 1e-5) << "block " << b << " column " << c << "\n"
                             << numeric.transpose() << "\n"
                             << column.transpose();
    }
  }
  std::printf("[ figures  ] worst relative Jacobian difference to central differences: %.2e\n", worst);
}

// In a Ceres problem with the quaternion manifold: state i and the biases held, state j perturbed by 0.1
// rad, 10 cm and 0.2 m/s comes back to the truth (the factor's 9 residuals fix j's 9 degrees of freedom).
TEST(ImuFactor, SolvesForTheNextStateWithTheQuaternionManifold) {
  const test::Motion motion = test::ordinary_motion();
  test::SyntheticImu imu;
  imu.bias = some_bias();
  const std::vector<ImuSample> samples = imu.samples(motion, 0.0, 1.5);
  const ImuPreintegration interval = preintegrate(samples, 500'000'000, 750'000'000, imu.bias, imu.noise);
  StateBlocks bi = blocks_of(motion.state(0.5), imu.bias);
  const NavState truth = motion.state(0.75);
  NavState start = truth;
  start.R_wb = truth.R_wb * so3::exp(Eigen::Vector3d(0.05, -0.06, 0.06));
  start.p_wb += Eigen::Vector3d(0.1, 0.0, -0.05);
  start.v_wb += Eigen::Vector3d(0.0, 0.2, 0.1);
  StateBlocks bj = blocks_of(start, imu.bias);
  ceres::Problem problem;
  problem.AddResidualBlock(ImuFactor::create(interval, imu.gravity_w()), nullptr, bi.q, bi.p, bi.v, bi.bg, bi.ba, bj.q,
                           bj.p, bj.v);
  for (double* block : {bi.q, bi.p, bi.v, bi.bg, bi.ba}) problem.SetParameterBlockConstant(block);
  problem.SetManifold(bj.q, new ceres::EigenQuaternionManifold);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  ASSERT_EQ(summary.termination_type, ceres::CONVERGENCE) << summary.BriefReport();
  const Eigen::Matrix3d R_j = Eigen::Quaterniond(bj.q[3], bj.q[0], bj.q[1], bj.q[2]).normalized().toRotationMatrix();
  EXPECT_LT(so3::log(R_j.transpose() * truth.R_wb).norm(), 1e-5);
  EXPECT_LT((Eigen::Vector3d(bj.p[0], bj.p[1], bj.p[2]) - truth.p_wb).norm(), 1e-5);
  EXPECT_LT((Eigen::Vector3d(bj.v[0], bj.v[1], bj.v[2]) - truth.v_wb).norm(), 5e-5);
}

TEST(BiasRandomWalkFactor, WhitensTheBiasChangeByTheRandomWalkOverTheInterval) {
  ImuNoise noise;
  ImuPreintegration interval(ImuBias{}, noise);
  for (int k = 0; k < 100; ++k) interval.integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 9.81), 0.005);
  std::unique_ptr<ceres::CostFunction> cost(BiasRandomWalkFactor::create(interval));
  const double bg_i[3] = {0.0, 0.0, 0.0};
  const double ba_i[3] = {0.1, 0.0, 0.0};
  const double bg_j[3] = {1e-5, 0.0, 0.0};
  const double ba_j[3] = {0.1, 0.003, 0.0};
  const double* parameters[] = {bg_i, ba_i, bg_j, ba_j};
  double residual[6];
  ASSERT_TRUE(cost->Evaluate(parameters, residual, nullptr));
  EXPECT_NEAR(residual[0], 1e-5 / (noise.gyro_random_walk * std::sqrt(0.5)), 1e-9);
  EXPECT_NEAR(residual[4], 0.003 / (noise.accel_random_walk * std::sqrt(0.5)), 1e-9);
  EXPECT_EQ(residual[3], 0.0);
  EXPECT_THROW(BiasRandomWalkFactor(ImuPreintegration{}), std::invalid_argument);
}

// The first-order propagation of the start state's and the bias's uncertainty against a Monte Carlo of
// perturbed starts and biases through the same (noise-free) preintegration.
TEST(Propagation, CovarianceMatchesAMonteCarloOfStartAndBiasErrors) {
  const test::Motion motion = test::ordinary_motion();
  test::SyntheticImu imu;
  imu.noise = ImuNoise{0.0, 0.0, 0.0, 0.0};
  const std::vector<ImuSample> samples = imu.samples(motion, 0.0, 1.5);
  const ImuPreintegration interval = preintegrate(samples, 300'000'000, 800'000'000, {}, imu.noise);
  NavStateEstimate start;
  start.state = motion.state(0.3);
  Eigen::Matrix<double, 9, 1> sigmas;
  sigmas << 0.01, 0.01, 0.01, 0.05, 0.05, 0.05, 0.03, 0.03, 0.03;
  start.covariance = sigmas.cwiseAbs2().asDiagonal();
  Eigen::Matrix<double, 6, 6> bias_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  bias_covariance.diagonal() << 1e-5, 1e-5, 1e-5, 4e-3, 4e-3, 4e-3;
  const NavStateEstimate end = propagate(start, interval, ImuBias{}, imu.gravity_w(), bias_covariance);
  const NavState predicted = interval.predict(start.state, imu.gravity_w());
  EXPECT_LT((end.state.p_wb - predicted.p_wb).norm(), 1e-12);

  std::mt19937_64 random(3);
  std::normal_distribution<double> unit(0.0, 1.0);
  constexpr int kRuns = 20000;
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> bias_llt(bias_covariance);
  Matrix9d spread = Matrix9d::Zero();
  for (int run = 0; run < kRuns; ++run) {
    Eigen::Matrix<double, 9, 1> e;
    Eigen::Matrix<double, 6, 1> d;
    for (int k = 0; k < 9; ++k) e[k] = sigmas[k] * unit(random);
    for (int k = 0; k < 6; ++k) d[k] = unit(random);
    d = bias_llt.matrixL() * d;
    NavState perturbed = start.state;
    perturbed.R_wb = start.state.R_wb * so3::exp(e.head<3>());
    perturbed.v_wb += e.segment<3>(3);
    perturbed.p_wb += e.tail<3>();
    ImuBias bias;
    bias.gyro_rad_s = d.head<3>();
    bias.accel_m_s2 = d.tail<3>();
    const NavState moved = interval.predict(perturbed, imu.gravity_w(), bias);
    Eigen::Matrix<double, 9, 1> error;
    error.head<3>() = so3::log(end.state.R_wb.transpose() * moved.R_wb);
    error.segment<3>(3) = moved.v_wb - end.state.v_wb;
    error.tail<3>() = moved.p_wb - end.state.p_wb;
    spread += error * error.transpose() / kRuns;
  }
  for (int block = 0; block < 3; ++block) {
    const double expected = end.covariance.block<3, 3>(3 * block, 3 * block).trace();
    const double measured = spread.block<3, 3>(3 * block, 3 * block).trace();
    std::printf("[ figures  ] block %d: propagated trace %.4e, Monte Carlo %.4e\n", block, expected, measured);
    EXPECT_NEAR(measured / expected, 1.0, 0.05) << "block " << block;
  }
  // The cross terms, as correlations (their traces mix signs).
  const Eigen::Matrix<double, 9, 1> scale = end.covariance.diagonal().cwiseSqrt().cwiseInverse();
  const Matrix9d correlation_difference = scale.asDiagonal() * (spread - end.covariance) * scale.asDiagonal();
  EXPECT_LT(correlation_difference.cwiseAbs().maxCoeff(), 0.03);
}

// A 2 s blackout bridged on the IMU alone (EuRoC white noise, bias known): chained over 8 intervals, the
// true state stays inside the propagated covariance: over 200 noise seeds the mean normalized error
// squared (NEES) of the 9-dof end state is 9 within its sampling spread.
TEST(Propagation, ABlackoutOfTwoSecondsKeepsTheTrueStateInsideItsCovariance) {
  const test::Motion motion = test::ordinary_motion();
  constexpr int kSeeds = 200;
  double nees_sum = 0.0;
  double worst_position_m = 0.0;
  double position_sigma_m = 0.0;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    test::SyntheticImu imu;
    imu.noisy = true;
    imu.noise.gyro_random_walk = 0.0;
    imu.noise.accel_random_walk = 0.0;
    imu.seed = static_cast<std::uint64_t>(seed);
    const std::vector<ImuSample> samples = imu.samples(motion, 0.0, 2.5);
    NavStateEstimate estimate;
    estimate.state = motion.state(0.25);
    for (int k = 0; k < 8; ++k) {
      const double t0 = 0.25 + 0.25 * k;
      const ImuPreintegration interval =
          preintegrate(samples, std::llround(t0 * 1e9), std::llround((t0 + 0.25) * 1e9), {}, imu.noise);
      estimate = propagate(estimate, interval, ImuBias{}, imu.gravity_w());
    }
    const NavState truth = motion.state(2.25);
    Eigen::Matrix<double, 9, 1> error;
    error.head<3>() = so3::log(estimate.state.R_wb.transpose() * truth.R_wb);
    error.segment<3>(3) = truth.v_wb - estimate.state.v_wb;
    error.tail<3>() = truth.p_wb - estimate.state.p_wb;
    nees_sum += error.dot(estimate.covariance.ldlt().solve(error));
    worst_position_m = std::max(worst_position_m, error.tail<3>().norm());
    position_sigma_m = std::sqrt(estimate.covariance.block<3, 3>(6, 6).trace());
  }
  const double mean_nees = nees_sum / kSeeds;
  std::printf(
      "[ figures  ] 2 s on the IMU alone, %d seeds: mean NEES %.2f (9 expected), position error worst %.1f mm, "
      "propagated 1-sigma %.1f mm\n",
      kSeeds, mean_nees, worst_position_m * 1e3, position_sigma_m * 1e3);
  // The mean of 200 chi-square(9) draws has a standard deviation of sqrt(18 / 200) = 0.3.
  EXPECT_NEAR(mean_nees, 9.0, 1.5);
}

}  // namespace
}  // namespace heslam

// Motion-only optimization with IMU factors (issue 34): known answers from a body turning at a constant
// rate with a constant acceleration, its exact IMU readings, and stereo observations of known points.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "components/core/imu/preintegration.hpp"
#include "components/core/tracking/inertial_pose_optimization.hpp"
#include "components/core/tracking/motion_only_ba.hpp"
#include "synthetic_scene.hpp"

namespace heslam {
namespace {

constexpr double kDt = 0.05;                     // one frame at 20 Hz
const Eigen::Vector3d kGravity(0.3, -9.7, 1.2);  // the tracker's world is the first camera's: gravity tilted

struct Scenario {
  NavState previous;
  NavState current;
  ImuPreintegration preintegration;
  Pose3 T_cb = Pose3::Identity();
};

// R(t) = R0 Exp(w t), a_w constant: gyro w, accel R(t)^T (a_w - g), sampled at 200 Hz over [0, kDt].
Scenario make_scenario() {
  const Eigen::Vector3d w(0.4, -0.3, 0.5);
  const Eigen::Vector3d a_w(0.6, 0.2, -0.4);
  Scenario s;
  s.previous.R_wb = Eigen::AngleAxisd(0.2, Eigen::Vector3d(1.0, 0.5, -0.2).normalized()).toRotationMatrix();
  s.previous.p_wb = Eigen::Vector3d(0.3, -0.1, 0.2);
  s.previous.v_wb = Eigen::Vector3d(0.5, 0.1, -0.2);
  const auto R_at = [&](double t) {
    return Eigen::Matrix3d(s.previous.R_wb * Eigen::AngleAxisd(w.norm() * t, w.normalized()).toRotationMatrix());
  };
  std::vector<ImuSample> samples;
  for (int k = 0; k <= 10; ++k) {
    const double t = 0.005 * k;
    ImuSample sample;
    sample.stamp_ns = static_cast<std::int64_t>(5'000'000) * k;
    sample.gyro_rad_s = w;
    sample.accel_m_s2 = R_at(t).transpose() * (a_w - kGravity);
    samples.push_back(sample);
  }
  s.preintegration = preintegrate(samples, 0, static_cast<std::int64_t>(kDt * 1e9));
  s.current.R_wb = R_at(kDt);
  s.current.v_wb = s.previous.v_wb + a_w * kDt;
  s.current.p_wb = s.previous.p_wb + s.previous.v_wb * kDt + 0.5 * a_w * kDt * kDt;
  s.T_cb.linear() = Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()).toRotationMatrix();
  s.T_cb.translation() = Eigen::Vector3d(0.02, -0.07, 0.01);
  return s;
}

Pose3 camera_T_cw(const NavState& body, const Pose3& T_cb) {
  Pose3 T_wb = Pose3::Identity();
  T_wb.linear() = body.R_wb;
  T_wb.translation() = body.p_wb;
  return T_cb * T_wb.inverse();
}

InertialPoseConstraint make_constraint(const Scenario& s) {
  InertialPoseConstraint c;
  c.preintegration = s.preintegration;
  c.previous = s.previous;
  c.gravity_w = kGravity;
  c.T_cb = s.T_cb;
  return c;
}

// `count` points in front of the camera at T_cw, stereo every other one, pixel noise `sigma_px`.
std::vector<PoseObservation> observe(const PinholeStereo& camera, const Pose3& T_cw, int count, double sigma_px,
                                     std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<PoseObservation> observations;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p_c((test::uniform01(rng) - 0.5) * 6.0, (test::uniform01(rng) - 0.5) * 4.0,
                              2.0 + 8.0 * test::uniform01(rng));
    PoseObservation obs;
    obs.p_w = T_cw.inverse() * p_c;
    const Eigen::Vector2d uv = camera.project(p_c);
    obs.u_px = uv.x() + sigma_px * test::gaussian(rng);
    obs.v_px = uv.y() + sigma_px * test::gaussian(rng);
    obs.u_right_px = i % 2 == 0 ? camera.u_right(p_c) + sigma_px * test::gaussian(rng) : -1.0;
    observations.push_back(obs);
  }
  return observations;
}

double position_error_m(const Pose3& a, const Pose3& b) {
  return (a.inverse().translation() - b.inverse().translation()).norm();
}

TEST(InertialPoseOptimization, ExactDataGivesThePoseAndVelocityAndKeepsTheBiases) {
  const PinholeStereo camera = test::synthetic_camera();
  const Scenario s = make_scenario();
  const Pose3 T_cw = camera_T_cw(s.current, s.T_cb);
  const std::vector<PoseObservation> observations = observe(camera, T_cw, 200, 0.0, 3);
  Pose3 guess = T_cw;
  guess.translation() += Eigen::Vector3d(0.04, -0.03, 0.05);
  guess.linear() = Eigen::AngleAxisd(0.04, Eigen::Vector3d::UnitZ()).toRotationMatrix() * guess.linear();
  const InertialPoseResult result = optimize_pose_inertial(camera, observations, guess, make_constraint(s));
  ASSERT_TRUE(result.ok);
  EXPECT_EQ(result.inliers, 200);
  EXPECT_LT(position_error_m(result.T_cw, T_cw), 1e-5);
  EXPECT_LT(test::rotation_error_deg(result.T_cw, T_cw), 1e-4);
  EXPECT_LT((result.state.v_wb - s.current.v_wb).norm(), 1e-4);
  EXPECT_LT(result.state.bias.gyro_rad_s.norm(), 1e-6);
  EXPECT_LT(result.state.bias.accel_m_s2.norm(), 1e-4);
}

TEST(InertialPoseOptimization, TheImuFactorPullsAFewNoisyMatchesTowardsTheTruth) {
  // 12 matches with 2 px noise: the visual optimization alone is off by millimetres; the exact IMU from
  // an exact previous state brings the pose closer to the truth.
  const PinholeStereo camera = test::synthetic_camera();
  const Scenario s = make_scenario();
  const Pose3 T_cw = camera_T_cw(s.current, s.T_cb);
  int closer = 0;
  constexpr int kTrials = 10;
  for (int trial = 0; trial < kTrials; ++trial) {
    const std::vector<PoseObservation> observations = observe(camera, T_cw, 12, 2.0, 100 + trial);
    const MotionOnlyBaResult visual = optimize_pose(camera, observations, T_cw);
    const InertialPoseResult inertial = optimize_pose_inertial(camera, observations, T_cw, make_constraint(s));
    ASSERT_TRUE(inertial.ok);
    if (position_error_m(inertial.T_cw, T_cw) < position_error_m(visual.T_cw, T_cw)) ++closer;
  }
  EXPECT_GE(closer, 8) << "of " << kTrials;
}

TEST(InertialPoseOptimization, APreviousVelocityOffWithinItsPriorIsCorrectedTowardsTheTruth) {
  const PinholeStereo camera = test::synthetic_camera();
  const Scenario s = make_scenario();
  const Pose3 T_cw = camera_T_cw(s.current, s.T_cb);
  const std::vector<PoseObservation> observations = observe(camera, T_cw, 200, 0.0, 5);
  InertialPoseConstraint constraint = make_constraint(s);
  const Eigen::Vector3d offset(0.02, -0.01, 0.015);  // within 2 sigma of prior_velocity_m_s
  constraint.previous.v_wb += offset;
  const InertialPoseResult result = optimize_pose_inertial(camera, observations, T_cw, constraint);
  ASSERT_TRUE(result.ok);
  // The velocity propagated from the wrong one would be off by `offset` and the pose by offset x 50 ms
  // (1.35 mm); the exact matches (200 at 2-10 m: about 1 mm of position information) share the difference
  // with the IMU factor, whose velocity-position correlation moves the velocity towards the truth.
  EXPECT_LT(position_error_m(result.T_cw, T_cw), 1e-3);
  EXPECT_LT((result.state.v_wb - s.current.v_wb).norm(), 0.95 * offset.norm());
}

// The hand-written solver against the Ceres version of the same cost: the same optimum, the same outliers.
void expect_same_optimum(const InertialPoseResult& own, const InertialPoseResult& ceres) {
  ASSERT_TRUE(own.ok);
  ASSERT_TRUE(ceres.ok);
  EXPECT_EQ(own.outlier, ceres.outlier);
  EXPECT_EQ(own.inliers, ceres.inliers);
  EXPECT_LT(position_error_m(own.T_cw, ceres.T_cw), 1e-6);
  EXPECT_LT(test::rotation_error_deg(own.T_cw, ceres.T_cw), 1e-5);
  EXPECT_LT((own.state.v_wb - ceres.state.v_wb).norm(), 1e-5);
  EXPECT_LT((own.state.bias.gyro_rad_s - ceres.state.bias.gyro_rad_s).norm(), 1e-7);
  EXPECT_LT((own.state.bias.accel_m_s2 - ceres.state.bias.accel_m_s2).norm(), 1e-5);
}

TEST(InertialPoseOptimization, TheOwnSolverReachesTheCeresOptimumOnExactData) {
  const PinholeStereo camera = test::synthetic_camera();
  const Scenario s = make_scenario();
  const Pose3 T_cw = camera_T_cw(s.current, s.T_cb);
  const std::vector<PoseObservation> observations = observe(camera, T_cw, 200, 0.0, 3);
  Pose3 guess = T_cw;
  guess.translation() += Eigen::Vector3d(0.04, -0.03, 0.05);
  guess.linear() = Eigen::AngleAxisd(0.04, Eigen::Vector3d::UnitZ()).toRotationMatrix() * guess.linear();
  const InertialPoseConstraint constraint = make_constraint(s);
  const InertialPoseResult own = optimize_pose_inertial(camera, observations, guess, constraint);
  const InertialPoseResult ceres = optimize_pose_inertial_ceres(camera, observations, guess, constraint);
  expect_same_optimum(own, ceres);
  EXPECT_LT(position_error_m(own.T_cw, T_cw), 1e-6);
  EXPECT_LT((own.state.v_wb - s.current.v_wb).norm(), 1e-5);
}

TEST(InertialPoseOptimization, TheOwnSolverReachesTheCeresOptimumOnNoisyDataWithOutliers) {
  // 1 px noise, one match in ten moved by 20-40 px, the previous state and biases off within their priors,
  // and mono-only frames: each seed a different optimum away from the truth, the same for both solvers.
  const PinholeStereo camera = test::synthetic_camera();
  const Scenario s = make_scenario();
  const Pose3 T_cw = camera_T_cw(s.current, s.T_cb);
  for (int seed = 0; seed < 8; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937_64 rng(1000 + static_cast<std::uint64_t>(seed));
    std::vector<PoseObservation> observations = observe(camera, T_cw, 150, 1.0, 200 + seed);
    for (std::size_t i = 0; i < observations.size(); i += 10) {
      observations[i].u_px += (test::uniform01(rng) < 0.5 ? -1.0 : 1.0) * (20.0 + 20.0 * test::uniform01(rng));
    }
    if (seed % 4 == 3) {
      for (PoseObservation& obs : observations) obs.u_right_px = -1.0;
    }
    for (std::size_t i = 0; i < observations.size(); i += 7) observations[i].inv_sigma2 = 1.0 / 1.44;
    InertialPoseConstraint constraint = make_constraint(s);
    constraint.previous.v_wb += Eigen::Vector3d(0.01, -0.008, 0.005) * (seed % 3);
    constraint.previous.p_wb += Eigen::Vector3d(-0.0008, 0.0005, 0.001) * (seed % 2);
    constraint.previous_bias.gyro_rad_s = Eigen::Vector3d(0.002, -0.001, 0.003) * seed;
    constraint.previous_bias.accel_m_s2 = Eigen::Vector3d(-0.02, 0.03, 0.01) * seed;
    Pose3 guess = T_cw;
    guess.translation() += Eigen::Vector3d(0.01, -0.02, 0.015);
    guess.linear() = Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitX()).toRotationMatrix() * guess.linear();
    const InertialPoseResult own = optimize_pose_inertial(camera, observations, guess, constraint);
    const InertialPoseResult ceres = optimize_pose_inertial_ceres(camera, observations, guess, constraint);
    expect_same_optimum(own, ceres);
    EXPECT_GT(position_error_m(own.T_cw, T_cw), 1e-5);  // noisy: an optimum of its own, not the truth
  }
}

TEST(InertialPoseOptimization, NoObservationsLeaveTheGuess) {
  const PinholeStereo camera = test::synthetic_camera();
  const Scenario s = make_scenario();
  const Pose3 guess = camera_T_cw(s.current, s.T_cb);
  const InertialPoseResult result = optimize_pose_inertial(camera, {}, guess, make_constraint(s));
  EXPECT_FALSE(result.ok);
  EXPECT_TRUE(result.T_cw.isApprox(guess));
}

}  // namespace
}  // namespace heslam

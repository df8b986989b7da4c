// Pose covariance from motion-only BA's information: symmetric positive definite, shrinking with more
// inliers, and consistent with the actual error of the BA's estimate (Monte Carlo, known noise).
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include "components/core/tracking/motion_only_ba.hpp"
#include "components/core/tracking/pose_covariance.hpp"
#include "synthetic_scene.hpp"

namespace heslam {
namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

constexpr double kPixelSigma = 0.5;
constexpr double kDisparitySigmaRatio = 0.5;  // MotionOnlyBaOptions' default: the model the noise follows

Pose3 true_T_cw() {
  Pose3 T_cw = Pose3::Identity();
  T_cw.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, 1.0, -0.2).normalized()).toRotationMatrix();
  T_cw.translation() = Eigen::Vector3d(0.8, -0.3, 1.5);
  return T_cw;
}

// Points in front of the camera observed with Gaussian noise exactly as the BA models it: u, v with
// kPixelSigma, the disparity with kDisparitySigmaRatio times that (every third point monocular).
std::vector<PoseObservation> observe(const PinholeStereo& camera, const Pose3& T_cw, int count, std::mt19937_64& rng) {
  std::vector<PoseObservation> observations;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p_c((test::uniform01(rng) - 0.5) * 8.0, (test::uniform01(rng) - 0.5) * 6.0,
                              2.0 + 10.0 * test::uniform01(rng));
    PoseObservation obs;
    obs.p_w = T_cw.inverse() * p_c;
    const Eigen::Vector2d uv = camera.project(p_c);
    obs.u_px = uv.x() + kPixelSigma * test::gaussian(rng);
    obs.v_px = uv.y() + kPixelSigma * test::gaussian(rng);
    const double disparity = camera.bf() / p_c.z() + kDisparitySigmaRatio * kPixelSigma * test::gaussian(rng);
    obs.u_right_px = i % 3 == 0 ? -1.0 : obs.u_px - disparity;
    observations.push_back(obs);
  }
  return observations;
}

struct Estimate {
  Pose3 T_cw;
  PoseCovariance covariance;
};

Estimate estimate(const PinholeStereo& camera, const std::vector<PoseObservation>& observations) {
  MotionOnlyBaOptions options;
  options.disparity_sigma_ratio = kDisparitySigmaRatio;
  const MotionOnlyBaResult result = optimize_pose(camera, observations, true_T_cw(), options);
  std::vector<PoseObservation> inliers;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    if (!result.outlier[i]) inliers.push_back(observations[i]);
  }
  const std::optional<PoseCovariance> covariance = pose_covariance(camera, inliers, result.T_cw, kDisparitySigmaRatio);
  EXPECT_TRUE(covariance.has_value());
  return {result.T_cw, covariance.value_or(PoseCovariance{})};
}

// The error of an estimate in the covariance's coordinates: rotation and position of T_wc, world axes.
Vector6 error_wc(const Pose3& estimated_T_cw) {
  const Pose3 T_wc = estimated_T_cw.inverse();
  const Pose3 truth_wc = true_T_cw().inverse();
  Vector6 e;
  const Eigen::AngleAxisd rotation(T_wc.rotation() * truth_wc.rotation().transpose());
  e.head<3>() = rotation.angle() * rotation.axis();
  e.tail<3>() = T_wc.translation() - truth_wc.translation();
  return e;
}

TEST(PoseCovariance, SymmetricPositiveDefiniteAndShrinksWithMoreInliers) {
  const PinholeStereo camera = test::synthetic_camera();
  std::mt19937_64 rng(11);
  const Estimate few = estimate(camera, observe(camera, true_T_cw(), 60, rng));
  const Estimate many = estimate(camera, observe(camera, true_T_cw(), 600, rng));
  for (const Estimate* e : {&few, &many}) {
    const Matrix6& c = e->covariance.covariance_wc;
    EXPECT_LT((c - c.transpose()).cwiseAbs().maxCoeff(), 1e-18);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6>(c).eigenvalues().minCoeff(), 0.0);
    // The variance factor recovers the noise relative to the model's 1 px: kPixelSigma^2.
    EXPECT_NEAR(e->covariance.variance_factor, kPixelSigma * kPixelSigma, 0.1);
  }
  // Ten times the points: about a tenth of the variance, in rotation and in position.
  const Matrix6& a = few.covariance.covariance_wc;
  const Matrix6& b = many.covariance.covariance_wc;
  const double rotation_few = a.topLeftCorner(3, 3).trace(), rotation_many = b.topLeftCorner(3, 3).trace();
  const double position_few = a.bottomRightCorner(3, 3).trace(), position_many = b.bottomRightCorner(3, 3).trace();
  EXPECT_LT(rotation_many, 0.3 * rotation_few);
  EXPECT_LT(position_many, 0.3 * position_few);
}

// Over many noisy problems, the estimate's error weighed by its covariance (NEES) averages the 6 degrees
// of freedom: the covariance neither over- nor under-states the error, in these coordinates.
TEST(PoseCovariance, PredictsTheSpreadOfTheEstimate) {
  const PinholeStereo camera = test::synthetic_camera();
  std::mt19937_64 rng(5);
  constexpr int kTrials = 300;
  double nees = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const Estimate e = estimate(camera, observe(camera, true_T_cw(), 150, rng));
    const Vector6 error = error_wc(e.T_cw);
    nees += error.dot(e.covariance.covariance_wc.ldlt().solve(error));
  }
  nees /= kTrials;
  // chi2(6) averaged over 300 trials: 6 with a standard deviation of sqrt(12 / 300) = 0.2; the BA's
  // 95 % gating of inliers makes the residuals, hence the variance factor, a little small.
  EXPECT_GT(nees, 5.0);
  EXPECT_LT(nees, 7.5);
}

TEST(PoseCovariance, NoneWithoutEnoughConstraints) {
  const PinholeStereo camera = test::synthetic_camera();
  std::mt19937_64 rng(3);
  const std::vector<PoseObservation> two = observe(camera, true_T_cw(), 2, rng);  // 5 rows at most
  EXPECT_FALSE(pose_covariance(camera, two, true_T_cw(), kDisparitySigmaRatio).has_value());
  EXPECT_FALSE(pose_covariance(camera, {}, true_T_cw(), kDisparitySigmaRatio).has_value());
}

}  // namespace
}  // namespace heslam

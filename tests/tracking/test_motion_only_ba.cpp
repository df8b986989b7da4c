// Motion-only BA: recovers a known pose from noisy stereo/mono observations with gross outliers.
#include <gtest/gtest.h>

#include "components/core/tracking/motion_only_ba.hpp"
#include "synthetic_scene.hpp"

namespace heslam {
namespace {

struct Problem {
  std::vector<PoseObservation> observations;
  std::vector<bool> is_outlier;
};

Problem make_problem(const PinholeStereo& camera, const Pose3& T_cw, int count, double outlier_fraction,
                     std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  Problem problem;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p_c((test::uniform01(rng) - 0.5) * 8.0, (test::uniform01(rng) - 0.5) * 6.0,
                              2.0 + 10.0 * test::uniform01(rng));
    PoseObservation obs;
    obs.p_w = T_cw.inverse() * p_c;
    const Eigen::Vector2d uv = camera.project(p_c);
    obs.u_px = uv.x() + 0.5 * test::gaussian(rng);
    obs.v_px = uv.y() + 0.5 * test::gaussian(rng);
    obs.u_right_px = i % 3 == 0 ? -1.0 : camera.u_right(p_c) + 0.5 * test::gaussian(rng);
    const bool outlier = test::uniform01(rng) < outlier_fraction;
    if (outlier) {
      obs.u_px += 40.0 + 60.0 * test::uniform01(rng);
      obs.v_px -= 30.0 + 50.0 * test::uniform01(rng);
    }
    problem.observations.push_back(obs);
    problem.is_outlier.push_back(outlier);
  }
  return problem;
}

TEST(MotionOnlyBa, RecoversPerturbedPoseAndFlagsOutliers) {
  const PinholeStereo camera = test::synthetic_camera();
  Pose3 T_cw = Pose3::Identity();
  T_cw.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1.0, -0.1).normalized()).toRotationMatrix();
  T_cw.translation() = Eigen::Vector3d(0.4, -0.2, 1.1);
  const Problem problem = make_problem(camera, T_cw, 400, 0.15, 7);

  Pose3 guess = T_cw;
  guess.translation() += Eigen::Vector3d(0.05, -0.04, 0.06);
  guess.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()).toRotationMatrix() * guess.linear();

  const MotionOnlyBaResult result = optimize_pose(camera, problem.observations, guess);
  EXPECT_LT((result.T_cw.translation() - T_cw.translation()).norm(), 0.005);
  EXPECT_LT(test::rotation_error_deg(result.T_cw, T_cw), 0.05);
  int flagged_true = 0;
  int flagged_false = 0;
  for (std::size_t i = 0; i < problem.is_outlier.size(); ++i) {
    if (problem.is_outlier[i] && result.outlier[i]) ++flagged_true;
    if (!problem.is_outlier[i] && result.outlier[i]) ++flagged_false;
  }
  const int outliers = static_cast<int>(std::count(problem.is_outlier.begin(), problem.is_outlier.end(), true));
  EXPECT_EQ(flagged_true, outliers);        // every gross outlier is rejected
  EXPECT_LT(flagged_false, 400 * 8 / 100);  // about 5 % of inliers exceed the 95 % chi-square bound
}

TEST(MotionOnlyBa, ExactObservationsGiveExactPose) {
  const PinholeStereo camera = test::synthetic_camera();
  Pose3 T_cw = Pose3::Identity();
  T_cw.translation() = Eigen::Vector3d(-0.3, 0.1, 0.2);
  Problem problem = make_problem(camera, T_cw, 50, 0.0, 3);
  for (auto& obs : problem.observations) {  // remove the noise
    const Eigen::Vector3d p_c = T_cw * obs.p_w;
    obs.u_px = camera.project(p_c).x();
    obs.v_px = camera.project(p_c).y();
    if (obs.stereo()) obs.u_right_px = camera.u_right(p_c);
  }
  const MotionOnlyBaResult result = optimize_pose(camera, problem.observations, Pose3::Identity());
  EXPECT_LT((result.T_cw.translation() - T_cw.translation()).norm(), 1e-6);
  EXPECT_LT(test::rotation_error_deg(result.T_cw, T_cw), 1e-5);
  EXPECT_EQ(result.inliers, 50);
}

// The stereo residual is (u, v, disparity) with the disparity whitened by disparity_sigma_ratio x the
// keypoint sigma: a 1.5 px disparity error alone has chi2 (1.5 / 0.5)^2 = 9 > 7.815 at ratio 0.5
// (outlier) and 2.25 at ratio 1 (inlier), whatever u is.
TEST(MotionOnlyBa, DisparityErrorIsWhitenedByItsOwnSigma) {
  const PinholeStereo camera = test::synthetic_camera();
  const Pose3 T_cw = Pose3::Identity();
  Problem problem = make_problem(camera, T_cw, 60, 0.0, 5);
  for (auto& obs : problem.observations) {  // exact observations, every one stereo
    const Eigen::Vector3d p_c = T_cw * obs.p_w;
    obs.u_px = camera.project(p_c).x();
    obs.v_px = camera.project(p_c).y();
    obs.u_right_px = camera.u_right(p_c);
  }
  problem.observations[0].u_right_px -= 1.5;  // disparity 1.5 px too large, u and v exact
  for (const double ratio : {0.5, 1.0}) {
    MotionOnlyBaOptions options;
    options.disparity_sigma_ratio = ratio;
    const MotionOnlyBaResult result = optimize_pose(camera, problem.observations, T_cw, options);
    EXPECT_EQ(result.outlier[0], ratio == 0.5) << "ratio " << ratio;
    EXPECT_LT((result.T_cw.translation() - T_cw.translation()).norm(), 1e-3) << "ratio " << ratio;
  }
  MotionOnlyBaOptions bad;
  bad.disparity_sigma_ratio = 0.0;
  EXPECT_THROW(optimize_pose(camera, problem.observations, T_cw, bad), std::invalid_argument);
}

TEST(MotionOnlyBa, EmptyInputLeavesGuess) {
  const Pose3 guess = Pose3(Eigen::Translation3d(1, 2, 3));
  const MotionOnlyBaResult result = optimize_pose(test::synthetic_camera(), {}, guess);
  EXPECT_EQ(result.T_cw.translation(), guess.translation());
  EXPECT_EQ(result.inliers, 0);
}

}  // namespace
}  // namespace heslam

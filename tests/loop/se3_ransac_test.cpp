// SE(3) RANSAC on synthetic stereo correspondences with a known relative pose.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "components/core/loop/se3_ransac.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

struct Problem {
  PinholeStereo camera = test::euroc_like_camera();
  Pose3 T_ab = Pose3::Identity();
  std::vector<Se3Correspondence> correspondences;
  std::vector<bool> outlier;
};

// Keypoint noise at level 0; the disparity noise is half of it. The refined transform is the
// maximum-likelihood one, so its error scales with this: measured 0.35 mm / 0.012 deg at 0.3 px and
// 1.5 mm / 0.028 deg at 0.5 px with points at 1.5-6 m; the 1 mm / 0.01 deg bound needs 0.2 px.
constexpr double kPixelNoisePx = 0.2;

// Points seen by both cameras at 1-4 m, keypoint noise x level scale, stereo depth from a noisy
// disparity; a share of the correspondences is replaced by random wrong ones.
Problem make_problem(int count, double outlier_ratio, unsigned seed) {
  Problem problem;
  problem.T_ab.linear() = Eigen::AngleAxisd(0.17, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  problem.T_ab.translation() = Eigen::Vector3d(0.3, -0.05, 0.2);
  const Pose3 T_ba = problem.T_ab.inverse();
  const PinholeStereo& camera = problem.camera;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u_of(0.0, camera.width_px - 1.0);
  std::uniform_real_distribution<double> v_of(0.0, camera.height_px - 1.0);
  std::uniform_real_distribution<double> depth_of(1.0, 4.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> octave_of(0, 2);
  std::normal_distribution<double> noise(0.0, kPixelNoisePx);
  const auto measure = [&](const Eigen::Vector3d& p_c, double& sigma2, Eigen::Vector2d& uv, Eigen::Vector3d& p_meas) {
    const double scale = std::pow(1.2, octave_of(rng));
    sigma2 = scale * scale;
    uv = camera.project(p_c) + Eigen::Vector2d(noise(rng), noise(rng)) * scale;
    const double disparity = camera.bf() / p_c.z() + 0.5 * noise(rng) * scale;
    p_meas = camera.unproject(uv.x(), uv.y(), camera.bf() / disparity);
  };
  while (static_cast<int>(problem.correspondences.size()) < count) {
    const Eigen::Vector3d p_a = camera.unproject(u_of(rng), v_of(rng), depth_of(rng));
    Eigen::Vector3d p_b = T_ba * p_a;
    if (p_b.z() < 0.5 || !camera.in_image(camera.project(p_b).x(), camera.project(p_b).y())) continue;
    const bool outlier = unit(rng) < outlier_ratio;
    if (outlier) p_b = camera.unproject(u_of(rng), v_of(rng), depth_of(rng));
    Se3Correspondence c;
    measure(p_a, c.sigma2_a, c.uv_a_px, c.p_a);
    measure(p_b, c.sigma2_b, c.uv_b_px, c.p_b);
    problem.correspondences.push_back(c);
    problem.outlier.push_back(outlier);
  }
  return problem;
}

TEST(LoopSe3Ransac, RecoversKnownTransformWithFortyPercentOutliers) {
  const Problem problem = make_problem(600, 0.4, 3);
  const auto result = Se3Ransac().compute(problem.camera, problem.correspondences);
  ASSERT_TRUE(result.has_value());
  const double translation_error_m = (result->T_ab.translation() - problem.T_ab.translation()).norm();
  const double rotation_error_deg = test::rotation_error_rad(result->T_ab, problem.T_ab) * 180.0 / M_PI;
  EXPECT_LT(translation_error_m, 1e-3);
  EXPECT_LT(rotation_error_deg, 0.01);
  int wrong_inliers = 0;
  int true_inliers = 0;
  for (std::size_t i = 0; i < problem.outlier.size(); ++i) {
    if (!problem.outlier[i]) ++true_inliers;
    if (problem.outlier[i] && result->inlier[i]) ++wrong_inliers;
  }
  EXPECT_LE(wrong_inliers, 3);  // a random wrong match can reproject within the threshold by chance
  EXPECT_GT(result->inliers, 0.9 * true_inliers);
  EXPECT_LE(result->iterations, 300);
}

TEST(LoopSe3Ransac, SameSeedSameTransformBitForBit) {
  const Problem problem = make_problem(200, 0.4, 4);
  Se3RansacOptions options;
  options.seed = 17;
  const auto first = Se3Ransac(options).compute(problem.camera, problem.correspondences);
  const auto second = Se3Ransac(options).compute(problem.camera, problem.correspondences);
  ASSERT_TRUE(first.has_value());
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ(first->T_ab.matrix(), second->T_ab.matrix());
  EXPECT_EQ(first->inlier, second->inlier);
  EXPECT_EQ(first->iterations, second->iterations);
}

TEST(LoopSe3Ransac, RefusesBelowMinInliers) {
  // 15 correct correspondences among random ones: a consistent transform exists but is too weak.
  Problem problem = make_problem(15, 0.0, 5);
  const Problem noise = make_problem(60, 1.0, 6);
  problem.correspondences.insert(problem.correspondences.end(), noise.correspondences.begin(),
                                 noise.correspondences.end());
  EXPECT_FALSE(Se3Ransac().compute(problem.camera, problem.correspondences).has_value());
  Se3RansacOptions lenient;
  lenient.min_inliers = 10;
  EXPECT_TRUE(Se3Ransac(lenient).compute(problem.camera, problem.correspondences).has_value());
}

TEST(LoopSe3Ransac, RefusesTooFewCorrespondences) {
  const Problem problem = make_problem(10, 0.0, 7);
  EXPECT_FALSE(Se3Ransac().compute(problem.camera, problem.correspondences).has_value());
}

}  // namespace
}  // namespace heslam

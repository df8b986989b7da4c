// Local BA on synthetic keyframes with known poses and points.
#include <gtest/gtest.h>

#include <atomic>

#include "components/core/mapping/local_bundle_adjustment.hpp"
#include "tests/mapping/mapping_test_util.hpp"

namespace heslam {
namespace {

struct PerturbedProblem {
  test::SyntheticWorld world = test::make_room(1500, 31);
  test::TruthMap truth;
  double initial_translation_error_m = 0.0;
};

// Keyframes 2.. get ~3 cm / ~0.6 deg pose errors, points ~3 cm errors; keyframe 1 anchors the gauge.
PerturbedProblem make_problem(double pixel_noise_px) {
  PerturbedProblem problem;
  test::ViewOptions view_options;
  view_options.pixel_noise_px = pixel_noise_px;
  view_options.clutter = 0;
  problem.truth = test::make_truth_map(problem.world, 6, view_options);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (auto& [id, kf] : problem.truth.map.keyframes) {
    if (id == 1) continue;
    const Eigen::Vector3d dt(0.03 * noise(rng), 0.03 * noise(rng), 0.03 * noise(rng));
    const Eigen::Vector3d dr(0.01 * noise(rng), 0.01 * noise(rng), 0.01 * noise(rng));
    kf.T_wc.translation() += dt;
    kf.T_wc.linear() = Eigen::AngleAxisd(dr.norm(), dr.normalized()).toRotationMatrix() * kf.T_wc.linear();
    problem.initial_translation_error_m += dt.norm();
  }
  for (auto& [id, point] : problem.truth.map.points) {
    point.p_w += Eigen::Vector3d(0.03 * noise(rng), 0.03 * noise(rng), 0.03 * noise(rng));
  }
  return problem;
}

double translation_error_m(const test::TruthMap& truth) {
  double sum = 0.0;
  for (const auto& [id, kf] : truth.map.keyframes)
    sum += (kf.T_wc.translation() - truth.true_T_wc.at(id).translation()).norm();
  return sum;
}

TEST(LocalBundleAdjustment, ReachesNoiseLevelAndReducesPoseError) {
  constexpr double kPixelNoise = 0.5;
  auto problem = make_problem(kPixelNoise);
  MapChanges changes;
  const auto result =
      local_bundle_adjustment(problem.truth.map, 6, problem.world.camera, LocalBundleAdjustmentOptions{}, changes);
  EXPECT_EQ(result.fixed_keyframes, 1);
  EXPECT_EQ(result.free_keyframes, 5);
  EXPECT_GT(result.initial_rms_px, 5.0 * kPixelNoise);
  // Whitened residual per observation has 3 components (stereo) of sigma = noise: rms = noise * sqrt(3).
  EXPECT_LT(result.final_rms_px, 1.2 * kPixelNoise * std::sqrt(3.0));
  const double final_error = translation_error_m(problem.truth);
  EXPECT_LT(final_error, 0.2 * problem.initial_translation_error_m);
  for (const auto& [id, kf] : problem.truth.map.keyframes) {
    EXPECT_LT(test::rotation_error_rad(kf.T_wc, problem.truth.true_T_wc.at(id)), 0.005) << "keyframe " << id;
  }
  EXPECT_EQ(changes.changed_keyframes.size(), 5u);
  EXPECT_EQ(problem.truth.map.keyframes.at(1).T_wc.matrix(), problem.truth.true_T_wc.at(1).matrix());
}

TEST(LocalBundleAdjustment, RecoversTheTruthExactlyWithoutNoise) {
  auto problem = make_problem(0.0);
  MapChanges changes;
  const auto result =
      local_bundle_adjustment(problem.truth.map, 6, problem.world.camera, LocalBundleAdjustmentOptions{}, changes);
  // Keypoints are floats (~6e-5 px resolution at u = 700): "exact" means at that level.
  EXPECT_LT(result.final_rms_px, 1e-3);
  EXPECT_LT(translation_error_m(problem.truth), 1e-5);
  for (const auto& [id, point] : problem.truth.map.points) {
    EXPECT_LT((point.p_w - problem.truth.true_p_w.at(id)).norm(), 1e-4) << "point " << id;
  }
}

TEST(LocalBundleAdjustment, RemovesGrossOutliers) {
  auto problem = make_problem(0.5);
  // Corrupt 20 observations of keyframe 6 by 30 px.
  Keyframe& kf = problem.truth.map.keyframes.at(6);
  std::vector<std::pair<PointId, int>> corrupted;
  for (std::size_t i = 0; i < kf.point_ids.size() && corrupted.size() < 20; i += 7) {
    if (kf.point_ids[i] == kNoId) continue;
    kf.features.keypoints[i].u_px += 30.f;
    kf.features.u_right_px[i] += 30.f;
    corrupted.emplace_back(kf.point_ids[i], static_cast<int>(i));
  }
  MapChanges changes;
  const auto result =
      local_bundle_adjustment(problem.truth.map, 6, problem.world.camera, LocalBundleAdjustmentOptions{}, changes);
  EXPECT_GE(result.outliers_removed, 20);
  EXPECT_LT(result.outliers_removed, 40);
  for (const auto& [point_id, index] : corrupted) {
    EXPECT_NE(problem.truth.map.keyframes.at(6).point_ids[static_cast<std::size_t>(index)], point_id);
  }
  EXPECT_LT(translation_error_m(problem.truth), 0.2 * problem.initial_translation_error_m);
}

TEST(LocalBundleAdjustment, StopRequestEndsTheSolveAndKeepsAValidMap) {
  // Complete run for reference: how many times the solver asks, and the error it reaches.
  auto complete_problem = make_problem(0.5);
  int complete_asks = 0;
  LocalBundleAdjustmentOptions complete_options;
  complete_options.stop_requested = [&] {
    ++complete_asks;
    return false;
  };
  MapChanges complete_changes;
  const auto complete = local_bundle_adjustment(complete_problem.truth.map, 6, complete_problem.world.camera,
                                                complete_options, complete_changes);
  EXPECT_FALSE(complete.aborted);
  ASSERT_GT(complete_asks, 3);

  // A keyframe "arrives" after the solver's third iteration: it stops there, skips the second pass.
  auto problem = make_problem(0.5);
  int asks = 0;
  LocalBundleAdjustmentOptions options;
  options.stop_requested = [&] { return ++asks >= 3; };
  MapChanges changes;
  const auto result = local_bundle_adjustment(problem.truth.map, 6, problem.world.camera, options, changes);
  EXPECT_TRUE(result.aborted);
  EXPECT_EQ(asks, 3);
  for (const auto& [id, kf] : problem.truth.map.keyframes) EXPECT_TRUE(kf.T_wc.matrix().allFinite());
  // Part of the way: better than the start, not as good as the complete run.
  EXPECT_LT(result.final_rms_px, result.initial_rms_px);
  EXPECT_GE(result.final_rms_px, complete.final_rms_px);
  EXPECT_FALSE(changes.changed_keyframes.empty());
}

}  // namespace
}  // namespace heslam

// Alignment and APE on synthetic trajectories with a known transform, scale and error.
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "synthetic_trajectory.hpp"
#include "tools/eval/ape.hpp"

namespace heslam::eval {
namespace {

Sim3 known_transform(double scale) {
  Sim3 S;
  S.R = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.3, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
  S.t = Eigen::Vector3d(12.0, -4.0, 3.5);
  S.scale = scale;
  return S;
}

Sim3 inverse(const Sim3& S) {
  Sim3 inv;
  inv.R = S.R.transpose();
  inv.scale = 1.0 / S.scale;
  inv.t = -inv.scale * (inv.R * S.t);
  return inv;
}

AlignedPair pair_of(const Trajectory& gt, const Trajectory& est) { return associate(gt, est); }

TEST(EvalAlignment, UmeyamaRecoversAKnownSimilarity) {
  const Trajectory gt = test::figure_eight();
  Trajectory est = gt;
  const Sim3 S = known_transform(0.25);
  apply_sim3(est, inverse(S));  // est lives in a frame S away from gt, at a quarter of the scale

  const Sim3 found = compute_alignment(gt, est, AlignMode::sim3);
  EXPECT_TRUE(found.R.isApprox(S.R, 1e-12));
  EXPECT_LT((found.t - S.t).norm(), 1e-10);
  EXPECT_NEAR(found.scale, 0.25, 1e-12);

  const ApeResult ape = compute_ape(pair_of(gt, est), ApeOptions{.align = AlignMode::sim3});
  EXPECT_LT(ape.translation_m.max, 1e-10);
  EXPECT_LT(ape.rotation_deg.max, 1e-6);
}

TEST(EvalAlignment, Se3RecoversARigidTransformAndKeepsScale) {
  const Trajectory gt = test::figure_eight();
  Trajectory est = gt;
  apply_sim3(est, inverse(known_transform(1.0)));
  const ApeResult ape = compute_ape(pair_of(gt, est), ApeOptions{.align = AlignMode::se3});
  EXPECT_DOUBLE_EQ(ape.alignment.scale, 1.0);
  EXPECT_LT(ape.translation_m.rmse, 1e-10);
  // Without alignment the same estimate is far off.
  EXPECT_GT(compute_ape(pair_of(gt, est), ApeOptions{.align = AlignMode::none}).translation_m.rmse, 5.0);
}

TEST(EvalAlignment, OriginPutsTheFirstPosesTogether) {
  const Trajectory gt = test::figure_eight();
  Trajectory est = gt;
  apply_sim3(est, inverse(known_transform(1.0)));
  const ApeResult ape = compute_ape(pair_of(gt, est), ApeOptions{.align = AlignMode::origin});
  EXPECT_LT(ape.translation_errors_m.front(), 1e-12);
  EXPECT_LT(ape.translation_m.max, 1e-10);  // a rigid copy: every pose lands on its ground truth
}

// Each pose is visited twice and the estimate is offset by +d and -d along z on the two visits: the
// offsets are uncorrelated with the path, so Umeyama still finds the exact transform and every
// pair's error is exactly d; each visit is also rotated by a known angle.
TEST(EvalApe, KnownNoiseGivesTheExpectedError) {
  const Trajectory path = test::figure_eight(200);
  Trajectory gt;
  gt.name = "gt";
  for (std::size_t i = 0; i < path.size(); ++i) {
    gt.push_back(path.poses_wc[i], static_cast<std::int64_t>(2 * i), 0.2 * static_cast<double>(i));
    gt.push_back(path.poses_wc[i], static_cast<std::int64_t>(2 * i + 1), 0.2 * static_cast<double>(i) + 0.1);
  }
  constexpr double kOffsetM = 0.05;
  constexpr double kAngleRad = 0.01;
  Trajectory est = gt;
  est.name = "est";
  for (std::size_t i = 0; i < est.size(); ++i) {
    Pose3& T = est.poses_wc[i];
    T.translation().z() += (i % 2 == 0 ? kOffsetM : -kOffsetM);
    T.linear() =
        (T.linear() * Eigen::AngleAxisd(kAngleRad, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix()).eval();
  }
  apply_sim3(est, inverse(known_transform(1.0)));

  const ApeResult ape = compute_ape(pair_of(gt, est), ApeOptions{.align = AlignMode::se3});
  EXPECT_NEAR(ape.translation_m.rmse, kOffsetM, 1e-10);
  EXPECT_NEAR(ape.translation_m.min, kOffsetM, 1e-10);
  EXPECT_NEAR(ape.translation_m.max, kOffsetM, 1e-10);
  EXPECT_NEAR(ape.translation_m.std, 0.0, 1e-9);
  EXPECT_NEAR(ape.translation_m.sse, kOffsetM * kOffsetM * 400, 1e-8);
  EXPECT_EQ(ape.translation_m.count, 400u);
  EXPECT_NEAR(ape.rotation_deg.mean, kAngleRad * 180.0 / std::numbers::pi, 1e-8);
}

TEST(EvalErrorStatistics, MatchNumpyDefinitions) {
  const std::vector<double> errors = {1.0, 2.0, 4.0, 7.0};
  const ErrorStats s = compute_stats(errors);
  EXPECT_DOUBLE_EQ(s.mean, 3.5);
  EXPECT_DOUBLE_EQ(s.median, 3.0);  // mean of the two middle values
  EXPECT_DOUBLE_EQ(s.sse, 70.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(17.5));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(5.25));  // population, not sample
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 7.0);
}

TEST(EvalAlignment, TooFewOrStillPosesAreErrors) {
  const Trajectory gt = test::straight_line(2, 1.0);
  EXPECT_THROW(compute_alignment(gt, gt, AlignMode::se3), std::runtime_error);
  const Trajectory still = test::straight_line(5, 0.0);
  EXPECT_THROW(compute_alignment(test::straight_line(5, 1.0), still, AlignMode::sim3), std::runtime_error);
}

// A still camera: the positions carry no rotation, the se3 fit turns the estimate by whatever the
// noise suggests (the 129 deg on the still V101 clip), and the warning says so; origin alignment
// has no such problem. A moving trajectory with the same noise is not flagged.
TEST(AlignmentDegeneracy, StillOrStraightIsFlaggedMovingIsNot) {
  const Trajectory gt = test::still_wobble(200, 0.002);
  const Trajectory est = test::still_wobble(200, 0.002, 1.0);  // the same spread, other noise
  const std::optional<std::string> still = alignment_degeneracy(gt, est, compute_alignment(gt, est, AlignMode::se3));
  ASSERT_TRUE(still.has_value());
  EXPECT_NE(still->find("the alignment's rotation is ill-determined"), std::string::npos) << *still;

  Trajectory line = test::straight_line(100, 0.1);
  Trajectory noisy_line = line;
  for (std::size_t i = 0; i < noisy_line.size(); ++i) {
    noisy_line.poses_wc[i].translation().x() += 0.01 * std::sin(0.9 * static_cast<double>(i));
  }
  EXPECT_TRUE(alignment_degeneracy(line, noisy_line, compute_alignment(line, noisy_line, AlignMode::se3)).has_value());

  const Trajectory moving = test::figure_eight();
  Trajectory moving_est = moving;
  for (std::size_t i = 0; i < moving_est.size(); ++i) {
    moving_est.poses_wc[i].translation().z() += 0.1 * std::sin(0.37 * static_cast<double>(i));
  }
  EXPECT_EQ(alignment_degeneracy(moving, moving_est, compute_alignment(moving, moving_est, AlignMode::se3)),
            std::nullopt);
  // An exact estimate fixes every rotation, however little it moves.
  EXPECT_EQ(alignment_degeneracy(gt, gt, compute_alignment(gt, gt, AlignMode::se3)), std::nullopt);
}

}  // namespace
}  // namespace heslam::eval

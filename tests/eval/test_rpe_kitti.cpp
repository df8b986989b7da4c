// RPE pair selection (frames, metres, all pairs) and the KITTI drift metrics on straight drives whose
// errors are known in closed form.
#include <cmath>

#include <gtest/gtest.h>

#include "synthetic_trajectory.hpp"
#include "tools/eval/kitti_metrics.hpp"
#include "tools/eval/rpe.hpp"

namespace heslam::eval {
namespace {

// Ground truth drives 1 m per frame, the estimate 1.1 m per frame: every motion is 10 % too long.
AlignedPair stretched_drive() { return associate(test::straight_line(100, 1.0), test::straight_line(100, 1.1)); }

TEST(EvalRpe, FramesDeltaUsesConsecutiveBlocks) {
  const RpeResult rpe = compute_rpe(stretched_drive(), RpeOptions{.delta = 5, .unit = DeltaUnit::frames});
  ASSERT_EQ(rpe.pairs.size(), 19u);
  EXPECT_EQ(rpe.pairs.front(), (std::pair<std::size_t, std::size_t>{0, 5}));
  EXPECT_EQ(rpe.pairs.back(), (std::pair<std::size_t, std::size_t>{90, 95}));
  EXPECT_NEAR(rpe.translation_m.rmse, 0.5, 1e-12);
  EXPECT_NEAR(rpe.rotation_deg.max, 0.0, 1e-12);
  const RpeResult all =
      compute_rpe(stretched_drive(), RpeOptions{.delta = 5, .unit = DeltaUnit::frames, .all_pairs = true});
  EXPECT_EQ(all.pairs.size(), 95u);
}

// evo's metre pairs: emitted where the estimate's accumulated path reaches 10 m (11 m after 10
// frames of 1.1 m), consecutive emitted rows form the pairs.
TEST(EvalRpe, MetresDeltaWalksTheEstimatePath) {
  const RpeResult rpe = compute_rpe(stretched_drive(), RpeOptions{.delta = 10, .unit = DeltaUnit::meters});
  ASSERT_EQ(rpe.pairs.size(), 8u);
  EXPECT_EQ(rpe.pairs.front(), (std::pair<std::size_t, std::size_t>{10, 20}));
  EXPECT_EQ(rpe.pairs.back(), (std::pair<std::size_t, std::size_t>{80, 90}));
  EXPECT_NEAR(rpe.translation_m.rmse, 1.0, 1e-9);  // 10 m of ground truth vs 11 m estimated
}

TEST(EvalRpe, MetresAllPairsTakeTheNearestPathLengthWithinTolerance) {
  const RpeResult rpe =
      compute_rpe(stretched_drive(), RpeOptions{.delta = 10, .unit = DeltaUnit::meters, .all_pairs = true});
  ASSERT_EQ(rpe.pairs.size(), 91u);  // 9.9 m after 9 frames, from rows 0..90
  EXPECT_EQ(rpe.pairs.front(), (std::pair<std::size_t, std::size_t>{0, 9}));
  EXPECT_NEAR(rpe.translation_m.mean, 0.9, 1e-9);
}

TEST(EvalRpe, NoPairFitsIsAnError) {
  EXPECT_THROW(compute_rpe(stretched_drive(), RpeOptions{.delta = 500, .unit = DeltaUnit::meters}), std::runtime_error);
  EXPECT_THROW(compute_rpe(stretched_drive(), RpeOptions{.delta = 2.5, .unit = DeltaUnit::frames}), std::runtime_error);
}

// 1000 frames of 1 m against 1.01 m: a sub-sequence of L metres ends at the first frame beyond L,
// L + 1 frames later, so its error is 0.01 (L + 1) / L.
TEST(EvalKittiMetrics, ScaleDriftOfAStraightDrive) {
  const Trajectory gt = test::straight_line(1000, 1.0);
  const Trajectory est = test::straight_line(1000, 1.01);
  const KittiResult k = compute_kitti_metrics(gt, est);
  double expected_sum = 0.0;
  std::size_t expected_segments = 0;
  for (std::size_t first = 0; first < 1000; first += 10) {
    for (double length = 100; length <= 800; length += 100) {
      if (first + static_cast<std::size_t>(length) + 1 > 999) continue;
      expected_sum += 0.01 * (length + 1) / length;
      ++expected_segments;
    }
  }
  ASSERT_EQ(k.segments.size(), expected_segments);
  EXPECT_NEAR(k.translation_error_percent, 100.0 * expected_sum / static_cast<double>(expected_segments), 1e-9);
  EXPECT_NEAR(k.per_length[0].translation_error_percent, 1.01, 1e-9);
  EXPECT_NEAR(k.per_length[7].translation_error_percent, 100.0 * 0.01 * 801.0 / 800.0, 1e-9);
  EXPECT_NEAR(k.rotation_error_deg_per_100m, 0.0, 1e-9);
  double squared = 0.0;
  for (int i = 0; i < 1000; ++i) squared += (0.01 * i) * (0.01 * i);
  EXPECT_NEAR(k.ate_m, std::sqrt(squared / 1000.0), 1e-9);
  EXPECT_NEAR(k.rpe_m, 0.01, 1e-9);

  // Sim(3) alignment removes a pure scale error.
  const KittiResult aligned = compute_kitti_metrics(gt, est, KittiOptions{.align = AlignMode::sim3});
  EXPECT_NEAR(aligned.alignment.scale, 1.0 / 1.01, 1e-12);
  EXPECT_NEAR(aligned.translation_error_percent, 0.0, 1e-9);
  EXPECT_NEAR(aligned.ate_m, 0.0, 1e-9);
}

// An estimate that starts at frame 2 (like kitti_example_results) in its own frame: both are taken
// relative to that first frame, so a rigid copy has no error.
TEST(EvalKittiMetrics, StartsAtTheEstimatesFirstFrame) {
  const Trajectory gt = test::figure_eight(1200);
  std::vector<std::size_t> rows;
  for (std::size_t i = 2; i < gt.size(); ++i) rows.push_back(i);
  Trajectory est = gt.subset(rows);
  est.stamps_s.clear();
  Sim3 S;
  S.R = Eigen::AngleAxisd(1.0, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  S.t = Eigen::Vector3d(5, 6, 7);
  apply_sim3(est, S);
  const KittiResult k = compute_kitti_metrics(gt, est);
  EXPECT_EQ(k.pairs, gt.size() - 2);
  EXPECT_GT(k.segments.size(), 0u);
  EXPECT_NEAR(k.translation_error_percent, 0.0, 1e-9);
  EXPECT_NEAR(k.rotation_error_deg_per_100m, 0.0, 1e-6);
  EXPECT_NEAR(k.ate_m, 0.0, 1e-9);
}

TEST(EvalKittiMetrics, TooShortIsAnError) {
  EXPECT_THROW(compute_kitti_metrics(test::straight_line(50, 1.0), test::straight_line(50, 1.0)), std::runtime_error);
}

}  // namespace
}  // namespace heslam::eval

// Association: nearest stamp within max dt from the shorter trajectory (evo's rule), frame indices
// for stamp-less KITTI files, and clear errors when nothing pairs.
#include <stdexcept>

#include <gtest/gtest.h>

#include "synthetic_trajectory.hpp"
#include "tools/eval/association.hpp"

namespace heslam::eval {
namespace {

Trajectory stamped(std::initializer_list<double> stamps_s, const std::string& name) {
  Trajectory t;
  t.name = name;
  std::int64_t id = 0;
  for (const double s : stamps_s) t.push_back(Pose3::Identity(), id++, s);
  return t;
}

TEST(EvalAssociation, PairsNearestStampWithinMaxDt) {
  const Trajectory gt = stamped({0.00, 0.10, 0.20, 0.30, 0.40, 0.50}, "gt");
  const Trajectory est = stamped({0.004, 0.196, 0.33, 0.509}, "est");
  const AlignedPair pair = associate(gt, est, AssociationOptions{.max_dt_s = 0.01});
  EXPECT_TRUE(pair.by_time);
  EXPECT_EQ(pair.gt_rows, (std::vector<std::size_t>{0, 2, 5}));  // 0.33 is 0.03 from 0.30: dropped
  EXPECT_EQ(pair.est_rows, (std::vector<std::size_t>{0, 1, 3}));
  EXPECT_EQ(pair.size(), 3u);
  EXPECT_DOUBLE_EQ(pair.est.stamps_s[1], 0.196);
}

TEST(EvalAssociation, WalksTheShorterTrajectoryEvenWhenItIsTheGroundTruth) {
  const Trajectory gt = stamped({0.10, 0.30}, "gt");
  const Trajectory est = stamped({0.0, 0.05, 0.099, 0.15, 0.2, 0.25, 0.305}, "est");
  const AlignedPair pair = associate(gt, est, AssociationOptions{.max_dt_s = 0.01});
  EXPECT_EQ(pair.gt_rows, (std::vector<std::size_t>{0, 1}));
  EXPECT_EQ(pair.est_rows, (std::vector<std::size_t>{2, 6}));
}

TEST(EvalAssociation, TiesGoToTheEarlierStamp) {
  const Trajectory gt = stamped({0.0, 1.0, 2.0}, "gt");
  const Trajectory est = stamped({0.5}, "est");
  const AlignedPair pair = associate(gt, est, AssociationOptions{.max_dt_s = 0.5});
  EXPECT_EQ(pair.gt_rows, (std::vector<std::size_t>{0}));
}

TEST(EvalAssociation, OffsetShiftsTheEstimateClock) {
  const Trajectory gt = stamped({10.0, 10.1, 10.2}, "gt");
  const Trajectory est = stamped({0.0, 0.1, 0.2}, "est");
  const AlignedPair pair = associate(gt, est, AssociationOptions{.max_dt_s = 0.001, .est_offset_s = 10.0});
  EXPECT_EQ(pair.size(), 3u);
}

// A ground truth at 10 Hz moving at constant velocity and turning at a constant rate about one axis:
// linear position and slerp interpolation are exact there.
Pose3 constant_twist(double t_s) {
  Pose3 T = Pose3::Identity();
  T.linear() = Eigen::AngleAxisd(0.3 * t_s, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(1.0, -0.5, 0.25) * t_s;
  return T;
}

TEST(EvalAssociation, InterpolatesTheGroundTruthAtTheEstimateStampsPlusOffset) {
  Trajectory gt;
  gt.name = "gt";
  for (int k = 0; k <= 10; ++k) gt.push_back(constant_twist(0.1 * k), k, 0.1 * k);
  Trajectory est;
  est.name = "est";
  for (const double s : {-0.05, 0.0, 0.033, 0.5, 0.977, 0.99}) est.push_back(Pose3::Identity(), 0, s);
  const AlignedPair pair = associate(gt, est, AssociationOptions{.est_offset_s = 0.02, .interpolate_gt = true});
  // -0.05 + 0.02 is before the ground truth, 0.99 + 0.02 after it.
  EXPECT_EQ(pair.est_rows, (std::vector<std::size_t>{1, 2, 3, 4}));
  EXPECT_EQ(pair.gt_rows, (std::vector<std::size_t>{0, 0, 5, 9}));
  ASSERT_EQ(pair.gt.size(), 4u);
  for (std::size_t k = 0; k < pair.size(); ++k) {
    const double t_s = pair.est.stamps_s[k] + 0.02;
    EXPECT_DOUBLE_EQ(pair.gt.stamps_s[k], t_s);
    const Pose3 expected = constant_twist(t_s);
    EXPECT_LT((pair.gt.poses_wc[k].translation() - expected.translation()).norm(), 1e-12) << k;
    EXPECT_TRUE(pair.gt.poses_wc[k].rotation().isApprox(expected.rotation(), 1e-12)) << k;
  }
}

TEST(EvalAssociation, InterpolationTakesAStampWithinAMicrosecondAsTheGroundTruthsOwn) {
  Trajectory gt;
  gt.name = "gt";
  for (int k = 0; k <= 2; ++k) gt.push_back(constant_twist(0.1 * k), k, 1403636584.763555584 + 0.1 * k);
  Trajectory est;
  est.name = "est";
  est.push_back(Pose3::Identity(), 0, 1403636584.763555527);  // the same stamp, written with 57 ns less
  const AlignedPair pair = associate(gt, est, AssociationOptions{.interpolate_gt = true});
  ASSERT_EQ(pair.size(), 1u);
  EXPECT_EQ(pair.gt_rows[0], 0u);
}

TEST(EvalAssociation, InterpolationDoesNotBridgeAGap) {
  Trajectory gt;
  gt.name = "gt";
  for (const double s : {0.0, 0.1, 0.5, 0.6}) gt.push_back(constant_twist(s), 0, s);
  Trajectory est;
  est.name = "est";
  for (const double s : {0.05, 0.3, 0.55}) est.push_back(Pose3::Identity(), 0, s);
  const AlignedPair pair = associate(gt, est, AssociationOptions{.interpolate_gt = true, .max_gap_s = 0.2});
  EXPECT_EQ(pair.est_rows, (std::vector<std::size_t>{0, 2}));
}

TEST(EvalAssociation, ByFrameIndexWithoutStamps) {
  const Trajectory gt = test::straight_line(10, 1.0);
  Trajectory est = test::straight_line(10, 1.0);
  const std::vector<std::size_t> rows = {2, 3, 7};
  est = est.subset(rows);
  const AlignedPair pair = associate(gt, est);
  EXPECT_FALSE(pair.by_time);
  EXPECT_EQ(pair.gt_rows, rows);
}

TEST(EvalAssociation, NoOverlapAndMixedStampsAreErrors) {
  const Trajectory gt = stamped({0.0, 0.1}, "gt.txt");
  const Trajectory later = stamped({5.0, 5.1}, "est.txt");
  try {
    associate(gt, later);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no overlap between gt.txt and est.txt"), std::string::npos) << e.what();
  }
  Trajectory kitti = test::straight_line(3, 1.0);
  kitti.name = "poses.txt";
  try {
    associate(gt, kitti);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("poses.txt has no time stamps"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace heslam::eval

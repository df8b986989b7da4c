// Agreement with the figures evo and kitti-odom-eval publish for ../shared/data/trajectories
// (README there), to 1e-6 relative; plus the other files of that folder run through cleanly.
#include <gtest/gtest.h>

#include "test_support.hpp"
#include "tools/eval/ape.hpp"
#include "tools/eval/kitti_metrics.hpp"
#include "tools/eval/rpe.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::eval {
namespace {

constexpr double kRelativeTolerance = 1e-6;

#define EXPECT_RELATIVE(actual, expected) EXPECT_NEAR((actual), (expected), kRelativeTolerance* std::abs(expected))

std::filesystem::path trajectories() { return ::heslam::test::shared_dataset("trajectories"); }

AlignedPair kitti00(const char* estimate) {
  const auto evo = trajectories() / "evo";
  return associate(read_trajectory(evo / "KITTI_00_gt.txt"), read_trajectory(evo / estimate));
}

TEST(EvalPublishedFigures, EvoApeKitti00OrbSe3) {
  HESLAM_REQUIRE_SHARED_DATA("trajectories");
  const ApeResult ape = compute_ape(kitti00("KITTI_00_ORB.txt"), ApeOptions{.align = AlignMode::se3});
  EXPECT_EQ(ape.translation_m.count, 4541u);
  EXPECT_RELATIVE(ape.translation_m.rmse, 1.3034497145650266);
  EXPECT_RELATIVE(ape.translation_m.mean, 1.1569971285389768);
  EXPECT_RELATIVE(ape.translation_m.median, 1.065624769555848);
  EXPECT_RELATIVE(ape.translation_m.std, 0.6002822693968323);
  EXPECT_RELATIVE(ape.translation_m.min, 0.06931322021483087);
  EXPECT_RELATIVE(ape.translation_m.max, 3.587949120678954);
}

TEST(EvalPublishedFigures, EvoRpeKitti00Orb10Metres) {
  HESLAM_REQUIRE_SHARED_DATA("trajectories");
  const RpeResult rpe = compute_rpe(kitti00("KITTI_00_ORB.txt"), RpeOptions{.delta = 10, .unit = DeltaUnit::meters});
  EXPECT_EQ(rpe.pairs.size(), 353u);
  EXPECT_RELATIVE(rpe.translation_m.rmse, 0.22626134329310163);
}

TEST(EvalPublishedFigures, KittiOdomEvalSequence09Sim3) {
  HESLAM_REQUIRE_SHARED_DATA("trajectories");
  const Trajectory gt = read_trajectory(trajectories() / "kitti_gt_poses/09.txt");
  const Trajectory est = read_trajectory(trajectories() / "kitti_example_results/09.txt");
  ASSERT_EQ(est.frame_ids.front(), 2);  // the example result has the 13-column layout
  const KittiResult k = compute_kitti_metrics(gt, est, KittiOptions{.align = AlignMode::sim3});
  EXPECT_RELATIVE(k.translation_error_percent, 2.884112511407129);
  EXPECT_RELATIVE(k.rotation_error_deg_per_100m, 0.24905618674615418);
  EXPECT_RELATIVE(k.ate_m, 8.38661922878607);
  EXPECT_RELATIVE(k.rpe_m, 0.34341307706920193);
  EXPECT_RELATIVE(k.rpe_deg, 0.0633886066529585);
}

// The other files: their published figures are kept aside; here they must run and give sane values.
TEST(EvalPublishedFigures, OtherFilesRunThrough) {
  HESLAM_REQUIRE_SHARED_DATA("trajectories");
  const ApeResult sptam = compute_ape(kitti00("KITTI_00_SPTAM.txt"), ApeOptions{.align = AlignMode::se3});
  EXPECT_EQ(sptam.translation_m.count, 4541u);
  EXPECT_GT(sptam.translation_m.rmse, 0.5);
  EXPECT_LT(sptam.translation_m.rmse, 20.0);

  const auto evo = trajectories() / "evo";
  const Trajectory desk_gt = read_trajectory(evo / "fr2_desk_groundtruth.txt");
  const Trajectory desk_orb = read_trajectory(evo / "fr2_desk_ORB.txt");
  EXPECT_EQ(desk_gt.size(), 20957u);  // 20960 lines, 3 comments
  const AlignedPair desk = associate(desk_gt, desk_orb, AssociationOptions{.max_dt_s = 0.01});
  EXPECT_TRUE(desk.by_time);
  EXPECT_GT(desk.size(), 2000u);
  EXPECT_LE(desk.size(), desk_orb.size());
  for (std::size_t i = 0; i < desk.size(); ++i) ASSERT_LE(std::abs(desk.gt.stamps_s[i] - desk.est.stamps_s[i]), 0.01);
  const ApeResult desk_ape = compute_ape(desk, ApeOptions{.align = AlignMode::se3});
  EXPECT_LT(desk_ape.translation_m.rmse, 0.05);  // RGB-D ORB-SLAM2 on a desk: centimetres

  const KittiResult k10 = compute_kitti_metrics(read_trajectory(trajectories() / "kitti_gt_poses/10.txt"),
                                                read_trajectory(trajectories() / "kitti_example_results/10.txt"),
                                                KittiOptions{.align = AlignMode::sim3});
  EXPECT_GT(k10.segments.size(), 100u);
  EXPECT_GT(k10.translation_error_percent, 0.5);
  EXPECT_LT(k10.translation_error_percent, 10.0);

  // KITTI with the sequence's times associates by time and gives the frame-index result.
  const Trajectory gt_timed =
      read_trajectory(evo / "KITTI_00_gt.txt", ReadOptions{.times_path = evo / "KITTI_00_gt_times.txt"});
  const Trajectory orb_timed =
      read_trajectory(evo / "KITTI_00_ORB.txt", ReadOptions{.times_path = evo / "KITTI_00_gt_times.txt"});
  const ApeResult timed = compute_ape(associate(gt_timed, orb_timed), ApeOptions{.align = AlignMode::se3});
  EXPECT_RELATIVE(timed.translation_m.rmse, 1.3034497145650266);
}

}  // namespace
}  // namespace heslam::eval

// Readers and writers: round trips between formats, KITTI indices and times, EuRoC layouts and the
// extrinsic, and one-line errors naming file:line.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <stdexcept>

#include <gtest/gtest.h>

#include "synthetic_trajectory.hpp"
#include "test_support.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::eval {
namespace {

using test::figure_eight;
using test::scratch_dir;
using test::write_file;

// Largest element difference; a plain loop, because GCC 12 warns falsely (maybe-uninitialized) on
// Eigen's vectorised 4x4 cwiseAbs().maxCoeff() with AVX-512.
double max_abs_difference(const Pose3& a, const Pose3& b) {
  double largest = 0.0;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) largest = std::max(largest, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  }
  return largest;
}

void expect_same_poses(const Trajectory& a, const Trajectory& b, double tolerance) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_LE(max_abs_difference(a.poses_wc[i], b.poses_wc[i]), tolerance) << "pose " << i;
  }
}

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(EvalTrajectoryIo, TumRoundTripKeepsPosesAndStamps) {
  const Trajectory original = figure_eight();
  const auto path = scratch_dir() / "traj.txt";
  write_trajectory(path, original, Format::tum);
  const Trajectory read = read_trajectory(path);  // detected as TUM
  expect_same_poses(original, read, 1e-12);
  ASSERT_EQ(read.stamps_s.size(), original.size());
  for (std::size_t i = 0; i < read.size(); ++i) EXPECT_NEAR(read.stamps_s[i], original.stamps_s[i], 1e-9);
}

TEST(EvalTrajectoryIo, KittiRoundTripIsExact) {
  const Trajectory original = figure_eight();
  const auto path = scratch_dir() / "traj.txt";
  write_trajectory(path, original, Format::kitti);
  const Trajectory read = read_trajectory(path);
  expect_same_poses(original, read, 0.0);
  EXPECT_FALSE(read.has_stamps());
  EXPECT_EQ(read.frame_ids, original.frame_ids);
}

TEST(EvalTrajectoryIo, KittiWithMissingFramesWritesAndReadsTheIndex) {
  Trajectory original = figure_eight(50);
  std::vector<std::size_t> rows;
  for (std::size_t i = 3; i < 50; i += 2) rows.push_back(i);
  original = original.subset(rows);
  const auto path = scratch_dir() / "indexed.txt";
  write_trajectory(path, original, Format::kitti);
  const Trajectory read = read_trajectory(path, ReadOptions{.format = Format::kitti});
  EXPECT_EQ(read.frame_ids, original.frame_ids);
  expect_same_poses(original, read, 0.0);
}

TEST(EvalTrajectoryIo, KittiTimesGiveStampsByFrameIndex) {
  const auto dir = scratch_dir();
  write_file(dir / "times.txt", "0.0\n0.5\n1.0\n1.5\n");
  write_file(dir / "poses.txt",
             "1 1 0 0 0 0 1 0 0 0 0 1 0\n"
             "3 1 0 0 1 0 1 0 0 0 0 1 0\n");
  const Trajectory t = read_trajectory(dir / "poses.txt", ReadOptions{.times_path = dir / "times.txt"});
  ASSERT_EQ(t.stamps_s.size(), 2u);
  EXPECT_DOUBLE_EQ(t.stamps_s[0], 0.5);
  EXPECT_DOUBLE_EQ(t.stamps_s[1], 1.5);
  EXPECT_DOUBLE_EQ(t.position_m(1).x(), 1.0);
}

TEST(EvalTrajectoryIo, EurocRoundTripThroughNanosecondStamps) {
  Trajectory original = figure_eight();
  for (double& stamp_s : original.stamps_s) stamp_s += 1403636584.0;
  const auto path = scratch_dir() / "data.csv";
  write_trajectory(path, original, Format::euroc);
  const Trajectory read = read_trajectory(path);  // .csv -> EuRoC
  expect_same_poses(original, read, 1e-12);
  for (std::size_t i = 0; i < read.size(); ++i) EXPECT_NEAR(read.stamps_s[i], original.stamps_s[i], 1e-6);
}

TEST(EvalTrajectoryIo, ConversionTumToKittiToEurocKeepsPoses) {
  const Trajectory original = figure_eight();
  const auto dir = scratch_dir();
  write_trajectory(dir / "a.txt", original, Format::tum);
  write_trajectory(dir / "b.txt", read_trajectory(dir / "a.txt"), Format::kitti);
  Trajectory from_kitti = read_trajectory(dir / "b.txt", ReadOptions{.format = Format::kitti});
  from_kitti.stamps_s = original.stamps_s;
  write_trajectory(dir / "c.csv", from_kitti, Format::euroc);
  expect_same_poses(original, read_trajectory(dir / "c.csv"), 1e-12);
}

TEST(EvalTrajectoryIo, MalformedLinesNameFileAndLine) {
  const auto dir = scratch_dir();
  write_file(dir / "bad_number.txt", "# comment\n1.0 0 0 0 0 0 0 1\n2.0 0 0 x 0 0 0 1\n");
  EXPECT_EQ(error_of([&] { read_trajectory(dir / "bad_number.txt", ReadOptions{.format = Format::tum}); }),
            (dir / "bad_number.txt").string() + ":3: expected a number in column 4, got 'x'");
  write_file(dir / "short.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  EXPECT_NE(error_of([&] {
              read_trajectory(dir / "short.txt", ReadOptions{.format = Format::tum});
            }).find("short.txt:2: expected 8 columns"),
            std::string::npos);
  write_file(dir / "kitti.txt", "1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_NE(error_of([&] {
              read_trajectory(dir / "kitti.txt", ReadOptions{.format = Format::kitti});
            }).find("kitti.txt:1: expected 12 or 13 columns"),
            std::string::npos);
  write_file(dir / "empty.txt", "# nothing\n\n");
  EXPECT_NE(error_of([&] { read_trajectory(dir / "empty.txt"); }).find("empty.txt: no poses"), std::string::npos);
  EXPECT_NE(error_of([&] { read_trajectory(dir / "missing.txt"); }).find("cannot open"), std::string::npos);
  write_file(dir / "backwards.txt", "2.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n");
  EXPECT_NE(error_of([&] { read_trajectory(dir / "backwards.txt"); }).find("time stamps go backwards at pose 2"),
            std::string::npos);
  write_file(dir / "nine.txt", "1 2 3 4 5 6 7 8 9\n");
  EXPECT_NE(error_of([&] { read_trajectory(dir / "nine.txt"); }).find("nine.txt:1: cannot tell the format"),
            std::string::npos);
}

TEST(EvalTrajectoryIo, ParsesFormatNames) {
  EXPECT_EQ(parse_format("heslam"), Format::tum);
  EXPECT_EQ(parse_format("kitti"), Format::kitti);
  EXPECT_EQ(parse_format("euroc"), Format::euroc);
  EXPECT_FALSE(parse_format("bag").has_value());
}

// The 17-column state estimate (V1_01 head) and the 8-column ground truth (MH_01) both read; with
// the cam0 extrinsic the poses become T_wc = T_wb * T_bs.
TEST(EvalTrajectoryIo, ReadsBothEurocLayoutsAndAppliesTheExtrinsic) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  HESLAM_REQUIRE_SHARED_DATA("euroc_v101_head");
  const auto mh01 = ::heslam::test::shared_dataset("euroc_mh01_handheld") / "mav0";
  const Trajectory body = read_trajectory(mh01 / "state_groundtruth_estimate0/data.csv");
  ASSERT_EQ(body.size(), 160u);
  EXPECT_NEAR(body.stamps_s[0], 1403636584.763555584, 1e-6);
  EXPECT_NEAR(body.position_m(0).x(), 4.680366, 1e-12);
  const Eigen::Quaterniond q0(Eigen::Matrix3d(body.poses_wc[0].linear()));
  EXPECT_NEAR(std::abs(q0.w()), 0.5712011980, 1e-9);

  const Pose3 T_bs = read_euroc_extrinsic(mh01 / "cam0/sensor.yaml");
  EXPECT_NEAR(T_bs.translation().x(), -0.0216401454975, 1e-15);
  EXPECT_NEAR(T_bs.linear()(0, 1), -0.999880929698, 1e-15);
  const Trajectory camera = read_trajectory(mh01 / "state_groundtruth_estimate0/data.csv",
                                            ReadOptions{.extrinsic_path = mh01 / "cam0/sensor.yaml"});
  ASSERT_EQ(camera.size(), body.size());
  for (std::size_t i = 0; i < camera.size(); i += 40) {
    EXPECT_LT(max_abs_difference(camera.poses_wc[i], body.poses_wc[i] * T_bs), 1e-15);
  }

  const auto v101 = ::heslam::test::shared_dataset("euroc_v101_head") / "mav0";
  const Trajectory state = read_trajectory(v101 / "state_groundtruth_estimate0/data.csv");
  ASSERT_EQ(state.size(), 95u);
  EXPECT_NEAR(state.position_m(0).y(), 2.1834, 1e-12);
  EXPECT_LT(state.path_length_m(), 0.05);  // the clip is almost still (README: 1.7 cm)
}

TEST(EvalTrajectoryIo, BadExtrinsicIsOneClearLine) {
  const auto dir = scratch_dir();
  write_file(dir / "sensor.yaml", "T_BS:\n  cols: 4\n  rows: 4\n  data: [1, 0, 0]\n");
  EXPECT_EQ(error_of([&] { read_euroc_extrinsic(dir / "sensor.yaml"); }),
            (dir / "sensor.yaml").string() + ": T_BS.data: expected 16 numbers (row-major 4x4), got 3");
  write_file(dir / "other.yaml", "rate_hz: 20\n");
  EXPECT_EQ(error_of([&] { read_euroc_extrinsic(dir / "other.yaml"); }),
            (dir / "other.yaml").string() + ": no field T_BS");
}

}  // namespace
}  // namespace heslam::eval

namespace heslam::eval {
namespace {

// heslam's TUM and EuRoC files name the frame of their poses in a '#' header line (which evo and
// the KITTI-free readers skip as a comment); a file without it (another tool's) has no frame.
TEST(EvalTrajectoryIo, FrameHeaderRoundTripsInTumAndEuroc) {
  const std::filesystem::path dir = scratch_dir();
  Trajectory body = figure_eight(20);
  body.frame = PoseFrame::body;
  for (const Format format : {Format::tum, Format::euroc}) {
    const std::filesystem::path path = dir / (std::string("frame_") + format_name(format) + ".txt");
    write_trajectory(path, body, format);
    const Trajectory back = read_trajectory(path, ReadOptions{.format = format});
    ASSERT_TRUE(back.frame.has_value()) << format_name(format);
    EXPECT_EQ(*back.frame, PoseFrame::body);
    ASSERT_EQ(back.size(), body.size());
    EXPECT_LT(max_abs_difference(back.poses_wc[7], body.poses_wc[7]), 1e-15);
  }
  write_file(dir / "other_tool.txt", "# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n");
  EXPECT_FALSE(read_trajectory(dir / "other_tool.txt").frame.has_value());
  // A header line after the first pose is not a header.
  write_file(dir / "late.txt", "0 0 0 0 0 0 0 1\n# heslam frame: body\n1 1 0 0 0 0 0 1\n");
  EXPECT_FALSE(read_trajectory(dir / "late.txt").frame.has_value());
  EXPECT_EQ(pose_frame_from_header(std::string_view("# heslam frame: rectified (T_wc: ...)")), PoseFrame::rectified);
  EXPECT_FALSE(pose_frame_from_header(std::string_view("# heslam frame: imu")).has_value());
}

// The TUM column header names the pose by its frame: T_wb for body poses, T_wc for a camera's.
TEST(EvalTrajectoryIo, TumColumnHeaderNamesThePoseOfItsFrame) {
  const std::filesystem::path dir = scratch_dir();
  const auto first_line = [](const std::filesystem::path& path) {
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);
    return line;
  };
  Trajectory trajectory = figure_eight(5);
  trajectory.frame = PoseFrame::body;
  write_trajectory(dir / "body.txt", trajectory, Format::tum);
  EXPECT_EQ(first_line(dir / "body.txt"), "# timestamp tx ty tz qx qy qz qw (T_wb, heslam)");
  trajectory.frame = PoseFrame::rectified;
  write_trajectory(dir / "rectified.txt", trajectory, Format::tum);
  EXPECT_EQ(first_line(dir / "rectified.txt"), "# timestamp tx ty tz qx qy qz qw (T_wc, heslam)");
  EXPECT_EQ(read_trajectory(dir / "body.txt").frame, PoseFrame::body);
}

// --est-extrinsic on a body-frame file makes it camera poses, and says so.
TEST(EvalTrajectoryIo, ExtrinsicOnABodyFileMakesItCam0) {
  const std::filesystem::path dir = scratch_dir();
  Trajectory body = figure_eight(10);
  body.frame = PoseFrame::body;
  write_trajectory(dir / "body.txt", body);
  write_file(dir / "sensor.yaml",
             "T_BS:\n  cols: 4\n  rows: 4\n  data: [1, 0, 0, 0.1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n");
  const Trajectory camera = read_trajectory(dir / "body.txt", ReadOptions{.extrinsic_path = dir / "sensor.yaml"});
  EXPECT_EQ(camera.frame, PoseFrame::cam0);
}

}  // namespace
}  // namespace heslam::eval

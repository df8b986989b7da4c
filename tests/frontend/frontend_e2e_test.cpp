// heslam-frontend end to end: replay -> frontend -> recorder as real processes under
// heslam-supervisor, in lockstep, on the shipped pipeline files (config/pipelines/*.yaml). Each test
// is its own process (ctest) and uses its own DDS domain; children are stopped and reaped on every
// path (ChildProcess kills on destruction; the supervisor's children die with it).
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "components/core/camera/stereo_rectifier.hpp"
#include "test_support.hpp"
#include "tools/bench/frontend_offline/offline_run.hpp"
#include "tools/eval/ape.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

// A lockstep run of 160 EuRoC frames takes ~5 s on an idle 2-core box; this bounds a hung pipeline.
constexpr std::chrono::seconds kPipelineTimeout{300};
constexpr std::chrono::seconds kStopTimeout{20};

int test_domain() { return heslam::test::exclusive_domain_id(); }
// Other suites on this machine may pick the same domain (pid residues collide); a namespace of our
// own keeps their topics apart from ours anyway.
std::string test_namespace() { return "heslam_e2e_" + std::to_string(getpid()); }

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

struct PipelineRun {
  int exit_code = -1;
  std::string output;  // the supervisor's combined, prefixed output
  fs::path trajectory;
  fs::path keyframes;
  fs::path lost;
};

PipelineRun run_pipeline(const std::string& pipeline, const fs::path& dataset, const fs::path& dir,
                         const std::string& label) {
  PipelineRun run;
  run.trajectory = dir / (label + ".txt");
  run.keyframes = dir / (label + ".keyframes.txt");
  run.lost = dir / (label + ".lost.txt");
  test::ChildProcess supervisor(
      test::bin_dir() / "heslam-supervisor",
      {(test::source_dir() / "config/pipelines" / (pipeline + ".yaml")).string(), "--domain",
       std::to_string(test_domain()), "--namespace", test_namespace(), "--log-dir", (dir / "logs").string(), "--arg",
       "dataset=" + dataset.string(), "--arg", "output=" + run.trajectory.string()},
      dir, "supervisor_" + label);
  std::optional<int> code = supervisor.wait(kPipelineTimeout);
  if (!code) {
    supervisor.signal(SIGTERM);
    code = supervisor.wait(kStopTimeout);
  }
  run.exit_code = code.value_or(-1);
  run.output = supervisor.out() + supervisor.err();
  return run;
}

eval::Trajectory camera_ground_truth(const fs::path& dataset) {
  eval::ReadOptions options;
  options.extrinsic_path = dataset / "mav0/cam0/sensor.yaml";
  return eval::read_trajectory(dataset / "mav0/state_groundtruth_estimate0/data.csv", options);
}

// The ground truth in the estimate's frame: body poses as they are for the recorder's default
// ('# heslam frame: body'), else cam0 poses.
eval::Trajectory ground_truth_for(const fs::path& dataset, const eval::Trajectory& estimate) {
  if (estimate.frame == eval::PoseFrame::body) {
    return eval::read_trajectory(dataset / "mav0/state_groundtruth_estimate0/data.csv");
  }
  return camera_ground_truth(dataset);
}

double max_abs_difference(const Pose3& a, const Pose3& b) {
  double worst = 0.0;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  return worst;
}

TEST(FrontendEndToEnd, EurocMh01TracksEveryFrameAndMatchesTheOfflineChain) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("mh01");
  const PipelineRun run = run_pipeline("euroc_odometry", dataset, dir.path(), "mh01");
  ASSERT_EQ(run.exit_code, 0) << run.output;

  const eval::Trajectory estimate = eval::read_trajectory(run.trajectory);
  ASSERT_EQ(estimate.size(), 160u) << run.output;
  EXPECT_EQ(test::lost_entries(run.lost), 0);
  // By default the poses are of the body frame (EuRoC's T_BS), as the ground truth, so
  // rotation errors are real: compared as they are, no --extrinsic.
  ASSERT_EQ(estimate.frame, eval::PoseFrame::body) << "no '# heslam frame: body' header";
  const eval::Trajectory truth = ground_truth_for(dataset, estimate);
  const eval::ApeResult ape = eval::compute_ape(truth, estimate);
  ASSERT_EQ(ape.translation_m.count, 160u);
  const eval::ApeResult from_start =
      eval::compute_ape(truth, estimate, eval::ApeOptions{.align = eval::AlignMode::origin});
  std::printf(
      "[ figures  ] euroc_mh01_handheld over DDS: %zu frames, %zu keyframes, ATE rmse %.3f mm; rotation APE "
      "(body frame) rmse %.3f deg aligned se3, %.3f deg aligned at the first pose\n",
      estimate.size(), eval::read_trajectory(run.keyframes).size(), ape.translation_m.rmse * 1e3, ape.rotation_deg.rmse,
      from_start.rotation_deg.rmse);
  // Target 4 mm (ORB-SLAM2/3 with local mapping: 3.6 mm). This frontend alone, without a local mapper,
  // measures 4.1 mm — the offline chain's figure, bound 4.5 mm in tests/tracking as well.
  EXPECT_LT(ape.translation_m.rmse, 0.0045);
  // Rotation errors are real now. The rectified-camera poses measured 1.45 deg (se3) against the cam0
  // ground truth: the rectifying rotation R1, not the tracker. In the body frame, aligned at the first
  // pose, what remains is the tracker's rotation drift over the clip (0.17 deg with the local mapper,
  // docs/benchmarks.md); 0.5 deg bounds it with room and stays well below R1. Aligned se3 (position-only
  // Umeyama, as evo_ape -a) the 30 cm clip leaves the alignment's rotation loosely fixed and the
  // positional drift tilts it (0.76 deg with the local mapper); bound it below the 1.45 deg of before.
  EXPECT_LT(from_start.rotation_deg.rmse, 0.5);
  EXPECT_LT(ape.rotation_deg.rmse, 1.2);

  // The same chain without DDS (tools/bench/frontend_offline) gives the same trajectory, once put in
  // the same frame. The poses cross the wire as quaternions, so equality is to the last bits of a
  // double, not bit for bit.
  const bench::OfflineRun offline = bench::run_offline(bench::load_euroc_sequence(dataset), {});
  ASSERT_EQ(offline.frames.size(), estimate.size());
  const Pose3 T_B_rect = StereoRectifier(load_euroc_calibration(dataset / "mav0")).T_B_rect();
  double worst = 0.0;
  for (std::size_t k = 0; k < estimate.size(); ++k) {
    ASSERT_EQ(offline.frames[k].state, TrackingState::kOk) << "frame " << k;
    EXPECT_NEAR(estimate.stamps_s[k], static_cast<double>(offline.frames[k].stamp_ns) * 1e-9, 1e-6) << "frame " << k;
    worst = std::max(worst,
                     max_abs_difference(estimate.poses_wc[k], eval::to_pose_frame(offline.frames[k].T_wc, T_B_rect)));
  }
  std::printf("[ figures  ] largest pose element difference DDS vs offline chain: %.3g\n", worst);
  EXPECT_LT(worst, 1e-12);
  EXPECT_EQ(eval::read_trajectory(run.keyframes).size(), static_cast<std::size_t>(offline.keyframes));
}

TEST(FrontendEndToEnd, TwoLockstepRunsWriteIdenticalTrajectoryFiles) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("determinism");
  const PipelineRun first = run_pipeline("euroc_odometry", dataset, dir.path(), "first");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const PipelineRun second = run_pipeline("euroc_odometry", dataset, dir.path(), "second");
  ASSERT_EQ(second.exit_code, 0) << second.output;
  const std::string trajectory = read_text(first.trajectory);
  EXPECT_GT(trajectory.size(), 1000u);
  EXPECT_EQ(trajectory, read_text(second.trajectory));
  EXPECT_EQ(read_text(first.keyframes), read_text(second.keyframes));
  EXPECT_EQ(read_text(first.lost), read_text(second.lost));
}

// The full system (config/pipelines/euroc.yaml: local mapper and loop closer as well): the frontend
// mirrors the mapper's map and waits for the KeyframeDone of both, so the run stays deterministic and
// the refined keyframes make the trajectory better than the frontend alone.
TEST(FrontendEndToEnd, FullSystemDeterministicAndWithinFourMillimetres) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  if (!fs::exists(test::bin_dir() / "heslam-local-mapper")) GTEST_SKIP() << "heslam-local-mapper not built";
  const fs::path dataset = test::shared_dataset("euroc_mh01_handheld");
  const test::ScratchDir dir("mapper");
  const PipelineRun first = run_pipeline("euroc", dataset, dir.path(), "first");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const PipelineRun second = run_pipeline("euroc", dataset, dir.path(), "second");
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_EQ(read_text(first.trajectory), read_text(second.trajectory)) << first.output << second.output;
  EXPECT_EQ(read_text(first.keyframes), read_text(second.keyframes));

  const eval::Trajectory estimate = eval::read_trajectory(first.trajectory);
  ASSERT_EQ(estimate.size(), 160u) << first.output;
  EXPECT_EQ(test::lost_entries(first.lost), 0) << first.output;
  EXPECT_GT(eval::read_trajectory(first.keyframes).size(), 1u);
  const eval::ApeResult ape = eval::compute_ape(ground_truth_for(dataset, estimate), estimate);
  std::printf("[ figures  ] euroc_mh01_handheld, full system: %zu keyframes, ATE rmse %.3f mm\n",
              eval::read_trajectory(first.keyframes).size(), ape.translation_m.rmse * 1e3);
  EXPECT_LE(ape.translation_m.rmse, 0.004);
}

TEST(FrontendEndToEnd, EurocV101StillCameraStaysStill) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_v101_head");
  const fs::path dataset = test::shared_dataset("euroc_v101_head");
  const test::ScratchDir dir("v101");
  const PipelineRun run = run_pipeline("euroc_odometry", dataset, dir.path(), "v101");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const eval::Trajectory estimate = eval::read_trajectory(run.trajectory);
  ASSERT_EQ(estimate.size(), 95u) << run.output;
  double max_distance_m = 0.0;
  for (const Pose3& T_wc : estimate.poses_wc) max_distance_m = std::max(max_distance_m, T_wc.translation().norm());
  const eval::ApeResult ape = eval::compute_ape(ground_truth_for(dataset, estimate), estimate);
  std::printf(
      "[ figures  ] euroc_v101_head over DDS: path length %.1f mm, max distance from start %.1f mm, "
      "ATE rmse %.2f mm\n",
      estimate.path_length_m() * 1e3, max_distance_m * 1e3, ape.translation_m.rmse * 1e3);
  // Target: path length < 5 mm (measured 2.9 mm for the rectified camera, 4.1 mm for the body frame
  // the recorder writes: the body sits ~7 cm from the camera, so the rocking moves it more; 63 mm of
  // per-frame jitter without the tracker's stationary test, tests/tracking/test_stationary.cpp). The
  // vehicle rocks by 0.15 degrees in this clip: the test keeps the camera centre on those frames, so
  // the rotation is not read as translation.
  EXPECT_LT(estimate.path_length_m(), 0.005);
  EXPECT_LT(max_distance_m, 0.005);
  EXPECT_LT(ape.translation_m.rmse, 0.002);
}

TEST(FrontendEndToEnd, SyntheticRoomAteWithinOnePercentOfPathLength) {
  const test::ScratchDir dir("synth");
  const fs::path dataset = dir.path() / "room";
  test::ChildProcess synth(test::bin_dir() / "heslam-synth",
                           {"--preset", "room", "--frames", "120", "--threads", "2", "--out", dataset.string()},
                           dir.path(), "synth");
  ASSERT_EQ(synth.wait(kPipelineTimeout).value_or(-1), 0) << synth.err();

  const PipelineRun run = run_pipeline("synth_odometry", dataset, dir.path(), "room");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const eval::Trajectory estimate = eval::read_trajectory(run.trajectory);
  const eval::Trajectory truth = ground_truth_for(dataset, estimate);
  ASSERT_EQ(estimate.size(), truth.size()) << run.output;
  const eval::ApeResult ape = eval::compute_ape(truth, estimate);
  const double path_m = truth.path_length_m();
  std::printf("[ figures  ] synthetic room, %zu frames over DDS: path %.2f m, ATE rmse %.2f mm (%.2f %% of path)\n",
              estimate.size(), path_m, ape.translation_m.rmse * 1e3, 100.0 * ape.translation_m.rmse / path_m);
  EXPECT_GT(path_m, 1.0);
  EXPECT_LE(ape.translation_m.rmse, 0.01 * path_m);
}

TEST(FrontendProcess, BadConfigFieldExitsWithOneLine) {
  const test::ScratchDir dir("badconfig");
  const fs::path config = dir.path() / "frontend.yaml";
  std::ofstream(config) << "lockstep:\n  mapper_timeout_s: -4\n";
  test::ChildProcess frontend(test::bin_dir() / "heslam-frontend",
                              {"--domain", std::to_string(test_domain()), "--config", config.string()}, dir.path(),
                              "frontend");
  EXPECT_EQ(frontend.wait(std::chrono::seconds(30)).value_or(-1), 1);
  const std::string err = frontend.err();
  EXPECT_NE(err.find("field 'lockstep.mapper_timeout_s'"), std::string::npos) << err;
  EXPECT_NE(err.find("frontend.yaml"), std::string::npos) << err;
}

// The settings file (an ORB-SLAM2 settings file) is checked as strictly: a bad value ends the process
// with one line naming the file and the key.
TEST(FrontendProcess, BadSettingsKeyExitsWithOneLine) {
  const test::ScratchDir dir("badsettings");
  const fs::path settings = dir.path() / "MyCamera.yaml";
  std::ofstream(settings) << "%YAML:1.0\nORBextractor.nLevels: 40\n";
  test::ChildProcess frontend(test::bin_dir() / "heslam-frontend",
                              {"--domain", std::to_string(test_domain()), "--settings", settings.string()}, dir.path(),
                              "frontend");
  EXPECT_EQ(frontend.wait(std::chrono::seconds(30)).value_or(-1), 1);
  const std::string err = frontend.err();
  EXPECT_NE(err.find("ORBextractor.nLevels"), std::string::npos) << err;
  EXPECT_NE(err.find("MyCamera.yaml"), std::string::npos) << err;
}

// --check runs the replay's own check, which opens the dataset: each pipeline gets one of its layout
// (MH01 for EuRoC and the synthetic pipelines, which read the EuRoC layout; a three-frame KITTI
// sequence written here for KITTI).
TEST(FrontendProcess, ShippedPipelinesPassTheSupervisorCheck) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const test::ScratchDir dir("check");
  const fs::path kitti = dir.path() / "kitti_sequence";
  fs::create_directories(kitti / "image_0");
  fs::create_directories(kitti / "image_1");
  std::ofstream(kitti / "times.txt") << "0.0\n0.1\n0.2\n";
  std::ofstream(kitti / "calib.txt") << "P0: 50.0 0.0 32.0 0.0 0.0 50.0 24.0 0.0 0.0 0.0 1.0 0.0\n"
                                        "P1: 50.0 0.0 32.0 -27.0 0.0 50.0 24.0 0.0 0.0 0.0 1.0 0.0\n"
                                        "P2: 50.0 0.0 32.0 0.0 0.0 50.0 24.0 0.0 0.0 0.0 1.0 0.0\n"
                                        "P3: 50.0 0.0 32.0 0.0 0.0 50.0 24.0 0.0 0.0 0.0 1.0 0.0\n";
  for (const char* name : {"000000.png", "000001.png", "000002.png"}) {
    for (const char* side : {"image_0", "image_1"})
      cv::imwrite((kitti / side / name).string(), cv::Mat(48, 64, CV_8UC1, 128));
  }
  const fs::path euroc = test::shared_dataset("euroc_mh01_handheld");
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(test::source_dir() / "config/pipelines")) {
    const std::string pipeline = entry.path().stem().string();
    const fs::path dataset = pipeline.rfind("kitti", 0) == 0 ? kitti : euroc;
    std::vector<std::string> args{entry.path().string(), "--check"};
    if (pipeline.rfind("camera", 0) == 0) {
      // heslam-camera's pipeline plays the EuRoC folder as a camera, calibrated by its sensor.yaml files
      args.insert(args.end(), {"--arg", "source=" + euroc.string(), "--arg", "calibration=" + euroc.string()});
    } else if (!pipeline.starts_with("ros2_input")) {
      // ros2_input*: the source is a ROS 2 camera (heslam-ros2-input), not a dataset folder
      args.insert(args.end(), {"--arg", "dataset=" + dataset.string()});
    }
    // replay_spy writes no trajectory; the localize pipeline refuses to start without a saved map
    if (pipeline != "replay_spy") args.insert(args.end(), {"--arg", "output=/tmp/x.txt"});
    if (pipeline == "euroc_localize") args.insert(args.end(), {"--arg", "map=/tmp/x.map"});
    test::ChildProcess check(test::bin_dir() / "heslam-supervisor", args, dir.path(), "check_" + pipeline);
    EXPECT_EQ(check.wait(std::chrono::seconds(30)).value_or(-1), 0) << pipeline << ": " << check.out() << check.err();
    ++checked;
    // Its optional components switched on pass too (each must be in a host group, its files exist).
    std::ifstream file(entry.path());
    const std::string text((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    if (text.find("$(arg occupancy)") != std::string::npos) {
      args.insert(args.end(), {"--arg", "occupancy=heslam-occupancy"});
      test::ChildProcess on(test::bin_dir() / "heslam-supervisor", args, dir.path(), "check_occupancy_" + pipeline);
      EXPECT_EQ(on.wait(std::chrono::seconds(30)).value_or(-1), 0)
          << pipeline << " with occupancy: " << on.out() << on.err();
    }
  }
  EXPECT_GE(checked, 9);
}

}  // namespace
}  // namespace heslam

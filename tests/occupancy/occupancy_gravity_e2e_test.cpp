// heslam-occupancy in an inertial run (docs/occupancy.md, "The grid's up"): the synthetic room rendered
// with its IMU, through synth_inertial with heslam-occupancy. Once the frontend's IMU initialized, the
// odometry carries gravity; the process turns its grid so that its up is against it (a level height
// band, the gravity-aligned map of the recorder and the ROS 2 bridge) and fuses its clouds again.
// Known answer: the room's first camera is pitched and rolled by its trajectory's wiggles; the angle the
// process reports between the grid's up and the first camera's -y is that camera's tilt from vertical,
// which heslam-synth's exact trajectory (z up) gives. Every wait is bounded against hangs, never timed.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <regex>
#include <string>

#include "pipeline_runs.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 160;                      // 8 s at 20 Hz: the IMU initializes within the first 2 s
constexpr std::chrono::seconds kRunTimeout{900};  // bound of a hung lockstep run on a loaded machine

TEST(OccupancyGravity, InertialRoomGridIsTurnedAgainstTheImuGravity) {
  const test::ScratchDir dir("occupancy_gravity");
  const fs::path dataset = dir.path() / "room_imu";
  test::ChildProcess synth(test::bin_dir() / "heslam-synth",
                           {"--preset", "room", "--frames", std::to_string(kFrames), "--threads", "2", "--no-events",
                            "--imu", "--out", dataset.string()},
                           dir.path(), "synth");
  ASSERT_EQ(synth.wait(std::chrono::seconds(600)).value_or(-1), 0) << synth.err();
  auto supervisor = test::start_pipeline("synth_inertial", dataset, dir.path(), "run", test::exclusive_domain_id(),
                                         {"loop_closer=none", "occupancy=heslam-occupancy"});
  const int code = test::finish(*supervisor, kRunTimeout);
  const std::string output = supervisor->out() + supervisor->err();
  ASSERT_EQ(code, 0) << output;
  EXPECT_TRUE(fs::is_regular_file(dir.path() / "run.pgm")) << output;
  EXPECT_TRUE(fs::is_regular_file(dir.path() / "run.yaml")) << output;

  std::smatch found;
  const std::regex line(R"(grid up: against the last gravity, ([0-9.eE+-]+) deg from -y \((\d+) turns\))");
  ASSERT_TRUE(std::regex_search(output, found, line)) << output;
  const double reported_deg = std::stod(found[1]);
  EXPECT_GE(std::stoi(found[2]), 1);

  // The first camera's tilt from vertical: the angle between its -y and the world's z (up) in heslam-synth's
  // exact trajectory. heslam's world is the first keyframe's camera (the first frame's).
  const eval::Trajectory truth = test::camera_ground_truth(dataset);
  ASSERT_FALSE(truth.poses_wc.empty());
  const Eigen::Vector3d up_c = truth.poses_wc.front().rotation().transpose() * Eigen::Vector3d::UnitZ();
  const double truth_deg = std::acos(std::clamp(-up_c.y(), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  std::printf("grid up against the IMU's gravity: %.3f deg from the first camera's -y, truth %.3f deg\n", reported_deg,
              truth_deg);
  EXPECT_GT(truth_deg, 2.0) << "the room's first camera is tilted (pitch offset 5 deg): the check must be able to fail";
  EXPECT_NEAR(reported_deg, truth_deg, 0.5);
}

}  // namespace
}  // namespace heslam

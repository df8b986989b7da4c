// The loop closer's config: the 4-DoF pose graph's fields (pose_graph.four_dof, pose_graph.gravity_w,
// pose_graph.gravity_from_odometry).
#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "components/loop_closer/loop_closer_options.hpp"
#include "runtime/config.hpp"
#include "test_support.hpp"

namespace heslam::loop_closer {
namespace {

LoopCloserProcessOptions parse(const std::string& yaml) {
  return LoopCloserProcessOptions::from_config(runtime::Config::parse("%YAML:1.0\n---\n" + yaml, "closer.yaml"), {});
}

TEST(LoopCloserOptions, PoseGraphIsSixDofByDefault) {
  const LoopCloserProcessOptions options = parse("real_time: false\n");
  EXPECT_FALSE(options.closing.correction.pose_graph.four_dof);
  EXPECT_EQ(options.closing.correction.pose_graph.gravity_w, Eigen::Vector3d(0.0, 0.0, -1.0));
  EXPECT_TRUE(options.gravity_from_odometry);  // 4-DoF only once the odometry carries a gravity
  EXPECT_FALSE(parse("pose_graph:\n  gravity_from_odometry: false\n").gravity_from_odometry);
}

// Stereo runs: 6-DoF (no gravity ever comes); inertial runs: 4-DoF about the odometry's gravity.
TEST(LoopCloserOptions, ShippedConfigsKeepTheSixDofGraph) {
  for (const char* name : {"heslam-loop-closer.yaml", "heslam-loop-closer-proximity.yaml"}) {
    SCOPED_TRACE(name);
    const runtime::Config config = runtime::Config::load(test::source_dir() / "config/loop_closer" / name);
    const LoopCloserProcessOptions options = LoopCloserProcessOptions::from_config(config, {});
    EXPECT_FALSE(options.closing.correction.pose_graph.four_dof);
    EXPECT_EQ(options.closing.correction.pose_graph.gravity_w, Eigen::Vector3d(0.0, 0.0, -1.0));
    EXPECT_TRUE(options.gravity_from_odometry);
  }
}

TEST(LoopCloserOptions, ShippedConfigsMergeMapsWithTheDocumentedGate) {
  for (const char* name : {"heslam-loop-closer.yaml", "heslam-loop-closer-proximity.yaml"}) {
    SCOPED_TRACE(name);
    const runtime::Config config = runtime::Config::load(test::source_dir() / "config/loop_closer" / name);
    const LoopCloserProcessOptions options = LoopCloserProcessOptions::from_config(config, {});
    EXPECT_TRUE(options.closing.merging);
    EXPECT_EQ(options.closing.merge.max_unobserved_speed_mps, 10.0);
    EXPECT_EQ(options.closing.merge.min_drift_allowance_m, 1.0);
    EXPECT_TRUE(options.closing.merge.seam_bundle_adjustment);
    EXPECT_EQ(options.closing.merge.min_matches, 80);  // a merge has no drift gate: ORB-SLAM3's bar, not 40
    EXPECT_EQ(options.closing.merge.covisible_confirmations, 2);
    EXPECT_EQ(options.closing.merge.confirmation_matches, 40);
  }
  const LoopCloserProcessOptions off = parse(
      "merge:\n  enabled: false\n  max_unobserved_speed_mps: 0.0\n  min_matches: 40\n  covisible_confirmations: 3\n"
      "  confirmation_matches: 30\n");
  EXPECT_FALSE(off.closing.merging);
  EXPECT_EQ(off.closing.merge.max_unobserved_speed_mps, 0.0);
  EXPECT_EQ(off.closing.merge.min_matches, 40);
  EXPECT_EQ(off.closing.merge.covisible_confirmations, 3);
  EXPECT_EQ(off.closing.merge.confirmation_matches, 30);
}

// The global BA's IMU factors (docs/loop_closer.md, Global BA with IMU factors): off in the code and the
// loop closers' own configs, on with the inertial pipelines' overlay, the documented bounds, a bad value one line
// naming file and field.
TEST(LoopCloserOptions, GlobalBaImuIsOffByDefaultAndReadFromTheConfig) {
  EXPECT_FALSE(parse("real_time: false\n").global_ba_imu);
  for (const char* name : {"heslam-loop-closer.yaml", "heslam-loop-closer-proximity.yaml"}) {
    SCOPED_TRACE(name);
    const runtime::Config config = runtime::Config::load(test::source_dir() / "config/loop_closer" / name);
    const LoopCloserProcessOptions options = LoopCloserProcessOptions::from_config(config, {});
    EXPECT_FALSE(options.global_ba_imu);
    EXPECT_EQ(options.imu_buffer_s, 600.0);
    EXPECT_EQ(options.imu_wait_s, 2.0);
    EXPECT_EQ(options.imu_max_interval_s, 3.0);
    // The inertial pipelines lay config/loop_closer/inertial.yaml over it: on there, the rest kept.
    const LoopCloserProcessOptions inertial = LoopCloserProcessOptions::from_config(
        runtime::Config::load(std::vector<std::filesystem::path>{
            test::source_dir() / "config/loop_closer" / name, test::source_dir() / "config/loop_closer/inertial.yaml"}),
        {});
    EXPECT_TRUE(inertial.global_ba_imu);
    EXPECT_EQ(inertial.imu_buffer_s, 600.0);
    EXPECT_EQ(inertial.imu_max_interval_s, 3.0);
  }
  const LoopCloserProcessOptions on =
      parse("global_ba:\n  imu: true\n  imu_buffer_s: 60\n  imu_wait_s: 0.5\n  imu_max_interval_s: 1.5\n");
  EXPECT_TRUE(on.global_ba_imu);
  EXPECT_EQ(on.imu_buffer_s, 60.0);
  EXPECT_EQ(on.imu_wait_s, 0.5);
  EXPECT_EQ(on.imu_max_interval_s, 1.5);
  try {
    parse("global_ba:\n  imu_max_interval_s: -1\n");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("closer.yaml"), std::string::npos) << message;
    EXPECT_NE(message.find("global_ba.imu_max_interval_s"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(LoopCloserOptions, FourDofTakesTheGravityDirection) {
  const LoopCloserProcessOptions options = parse("pose_graph:\n  four_dof: true\n  gravity_w: [0.0, 9.81, 0]\n");
  EXPECT_TRUE(options.closing.correction.pose_graph.four_dof);
  EXPECT_EQ(options.closing.correction.pose_graph.gravity_w, Eigen::Vector3d(0.0, 9.81, 0.0));
}

TEST(LoopCloserOptions, ABadGravityDirectionIsOneLineNamingFileAndField) {
  for (const char* gravity : {"[0.0, -1.0]", "[0, 0, 0]", "[0, .nan, -1]"}) {
    SCOPED_TRACE(gravity);
    try {
      parse(std::string("pose_graph:\n  four_dof: true\n  gravity_w: ") + gravity + "\n");
      FAIL() << "expected an error";
    } catch (const std::runtime_error& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find("closer.yaml"), std::string::npos) << message;
      EXPECT_NE(message.find("pose_graph.gravity_w"), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
}

}  // namespace
}  // namespace heslam::loop_closer

// DDS Security end to end: the full synthetic pipeline (replay, frontend, local mapper, bag
// of words loop closer, recorder, supervisor) in secure mode (--arg security=DIR) gives the plain
// run's trajectory (lockstep: bit-identical input and processing), while a participant without
// credentials publishes every hostile sample class on the same domain for the
// whole run: stereo frames far ahead of the replay (the stray frame that truncated plain runs), a
// different calibration, NaN poses in Odometry, Keyframe and KeyframeState, 100 m loop corrections.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "pipeline_runs.hpp"
#include "security_folder.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 40;

using test::last_line;

std::unique_ptr<test::ChildProcess> start_intruder(const fs::path& dir, const std::string& mode, int domain) {
  // Longer than any run: killed when the test ends.
  return std::make_unique<test::ChildProcess>(
      test::bin_dir() / "heslam-test-secure-peer",
      std::vector<std::string>{"--domain", std::to_string(domain), mode, "--seconds", "3600"}, dir, "intruder_" + mode);
}

TEST(SecurePipeline, SynthRoomGivesThePlainTrajectoryWhileAnIntruderPublishes) {
  fs::path dataset;
  ASSERT_EQ(test::cached_synth("room", kFrames, dataset), "");
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("secure_pipeline");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());

  auto plain = test::start_pipeline("synth", dataset, dir.path(), "plain", domain);
  ASSERT_EQ(test::finish(*plain), 0) << plain->err();

  auto intruder = start_intruder(dir.path(), "publish-hostile", domain);
  auto secure = test::start_pipeline("synth", dataset, dir.path(), "secure", domain, {"security=" + security.string()});
  ASSERT_EQ(test::finish(*secure), 0) << secure->err();
  EXPECT_EQ(intruder->wait(std::chrono::milliseconds(0)), std::nullopt) << "the intruder stopped: " << intruder->err();

  const std::string summary = last_line(secure->err());
  std::cout << "secure run: " << summary << "\n";
  EXPECT_NE(summary.find("pipeline finished: tracked " + std::to_string(kFrames) + "/" + std::to_string(kFrames) +
                         " frames, 0 lost"),
            std::string::npos)
      << summary;

  const eval::Trajectory plain_poses = eval::read_trajectory(dir.path() / "plain.txt");
  const eval::Trajectory secure_poses = eval::read_trajectory(dir.path() / "secure.txt");
  ASSERT_EQ(plain_poses.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(secure_poses.size(), plain_poses.size());
  double max_difference_m = 0.0;
  for (std::size_t i = 0; i < plain_poses.size(); ++i) {
    EXPECT_DOUBLE_EQ(secure_poses.stamps_s[i], plain_poses.stamps_s[i]);
    const double difference_m = (secure_poses.poses_wc[i].translation() - plain_poses.poses_wc[i].translation()).norm();
    max_difference_m = std::max(max_difference_m, difference_m);
  }
  std::cout << "[ figures ] secure vs plain: " << secure_poses.size() << " poses, largest position difference "
            << max_difference_m << " m; ATE plain " << test::ate_rmse_m(dataset, dir.path() / "plain.txt")
            << " m, secure " << test::ate_rmse_m(dataset, dir.path() / "secure.txt") << " m\n";
  // Lockstep runs are repeatable to the last digit written; 1 um leaves room for text rounding only.
  EXPECT_LT(max_difference_m, 1e-6);
}

// --check verifies the folder and every identity the pipeline needs; a missing one is one line.
TEST(SecurePipeline, CheckNamesTheFolderAndAMissingIdentity) {
  const test::ScratchDir dir("secure_check");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());
  const fs::path pipeline = test::source_dir() / "config/pipelines/synth.yaml";
  // --check opens the dataset as the replay would (its own --check): a real one.
  fs::path dataset;
  ASSERT_EQ(test::cached_synth("room", kFrames, dataset), "");
  test::ChildProcess check(
      test::bin_dir() / "heslam-supervisor",
      {pipeline.string(), "--check", "--arg", "dataset=" + dataset.string(), "--arg", "security=" + security.string()},
      dir.path(), "check_ok");
  ASSERT_EQ(check.wait(std::chrono::seconds(60)), 0) << check.err();
  EXPECT_NE(check.out().find(", DDS security from " + security.string()), std::string::npos) << check.out();

  fs::remove_all(security / "identities/recorder");
  test::ChildProcess missing(
      test::bin_dir() / "heslam-supervisor",
      {pipeline.string(), "--check", "--arg", "dataset=" + dataset.string(), "--security", security.string()},
      dir.path(), "check_missing");
  ASSERT_EQ(missing.wait(std::chrono::seconds(60)), 1) << missing.out();
  EXPECT_EQ(last_line(missing.err()),
            "heslam-supervisor: " + pipeline.string() +
                ": component 'recorder': DDS security: " + (security / "identities/recorder/cert.pem").string() +
                " does not exist (make the folder with heslam-security init DIR; one more "
                "identity with heslam-security add DIR NAME:PUBLISH:SUBSCRIBE)");
}

}  // namespace
}  // namespace heslam

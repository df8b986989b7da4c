// Forged identities: a participant that copies the run's id (readable from /proc)
// and forges one component's samples on the full synthetic pipeline (replay, frontend, local mapper,
// bag of words loop closer, recorder) in lockstep. Plain DDS cannot authenticate, but it notices:
// two live writers claiming one role fail the run loudly (nonzero exit, the last line names the
// topic), and heslam-supervisor takes its components' status only from the processes it started.
// Secure mode (--arg security=DIR) refuses every forger: the run is the plain run without forgers.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <thread>

#include "pipeline_runs.hpp"
#include "security_folder.hpp"
#include "synth_render.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 40;
// Bound on the wait for the recorder's process to appear (start-up, not performance).
constexpr std::chrono::seconds kChildTimeout{60};

using test::last_line;

// heslam-test-secure-peer MODE without credentials, copying the run id of `supervisor`; longer than
// any run: killed when the test ends.
std::unique_ptr<test::ChildProcess> start_forger(const fs::path& dir, const std::string& mode, int domain,
                                                 pid_t supervisor, const std::vector<std::string>& more = {}) {
  std::vector<std::string> args{"--domain", std::to_string(domain),    mode, "--seconds", "3600",
                                "--run-of", std::to_string(supervisor)};
  args.insert(args.end(), more.begin(), more.end());
  return std::make_unique<test::ChildProcess>(test::bin_dir() / "heslam-test-secure-peer", args, dir, "forger_" + mode);
}

pid_t wait_for_child(pid_t supervisor, const std::string& comm) {
  const auto deadline = std::chrono::steady_clock::now() + kChildTimeout;
  pid_t pid = 0;
  while ((pid = test::child_pid(supervisor, comm)) == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return pid;
}

struct ForgedRun {
  int exit_code = -1;
  std::string summary;  // the supervisor's last line
  std::string err;
};

// The synth pipeline on its own domain with forger MODE copying its run id from the start.
ForgedRun run_with_forger(const std::string& mode, const std::string& label) {
  fs::path dataset;
  EXPECT_EQ(test::cached_synth("room", kFrames, dataset), "");
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("forged_" + label);
  auto supervisor = test::start_pipeline("synth", dataset, dir.path(), label, domain);
  std::vector<std::string> more;
  if (mode == "forge-status") {
    const pid_t recorder = wait_for_child(supervisor->pid(), "heslam-recorder");
    EXPECT_NE(recorder, 0) << "no recorder started: " << supervisor->err();
    more = {"--pid", std::to_string(recorder), "--name", "recorder"};
  }
  auto forger = start_forger(dir.path(), mode, domain, supervisor->pid(), more);
  ForgedRun run;
  run.exit_code = test::finish(*supervisor);
  run.err = supervisor->err();
  run.summary = last_line(run.err);
  EXPECT_EQ(forger->wait(std::chrono::milliseconds(0)), std::nullopt) << "the forger stopped: " << forger->err();
  std::cout << mode << ": exit " << run.exit_code << ", " << run.summary << "\n";
  return run;
}

// Forged poses with the run id: the recorder sees two live odometry writers; the run fails and says so.
TEST(SecurityForgery, PlainForgedOdometryWithTheRunIdFailsTheRunLoudly) {
  const ForgedRun run = run_with_forger("forge-odometry", "odometry");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.summary.find("pipeline failed: recorder: two live writers claimed one role on heslam/odometry"),
            std::string::npos)
      << run.err;
}

// A forged "recorder" status (its pid and the run id copied) never reaches the last line: refused,
// named, and the run fails.
TEST(SecurityForgery, PlainForgedRecorderStatusIsRefusedAndNamed) {
  const ForgedRun run = run_with_forger("forge-status", "status");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_EQ(run.summary.find("/forged/path.txt"), std::string::npos) << run.summary;
  EXPECT_NE(run.summary.find("pipeline failed: forged status of 'recorder' from a process this supervisor did not "
                             "start"),
            std::string::npos)
      << run.err;
}

// FrameDone forged in step with the frames: the replay sees two live writers pace it; the run fails.
TEST(SecurityForgery, PlainForgedFrameDoneFailsTheRunLoudly) {
  const ForgedRun run = run_with_forger("forge-frame-done", "frame_done");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.summary.find("two live writers claimed one role on heslam/lockstep/frame_done"), std::string::npos)
      << run.err;
}

// KeyframeDone of "local_mapper" with map_version 999999 for each keyframe: the frontend sees two
// live writers acknowledge as the mapper, stops waiting (no 30 s timeouts per keyframe) and the run fails.
TEST(SecurityForgery, PlainForgedKeyframeDoneFailsTheRunLoudlyWithoutWaiting) {
  const ForgedRun run = run_with_forger("forge-keyframe-done", "keyframe_done");
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.summary.find("two live writers claimed one role on heslam/lockstep/keyframe_done"), std::string::npos)
      << run.err;
  EXPECT_EQ(run.err.find("no KeyframeDone from the mapper"), std::string::npos) << run.err;
}

// Every forger at once against a secure run: none is authenticated, the run is the plain one.
TEST(SecurityForgery, SecurePipelineRefusesEveryForger) {
  fs::path dataset;
  ASSERT_EQ(test::cached_synth("room", kFrames, dataset), "");
  const int domain = test::exclusive_domain_id();
  const test::ScratchDir dir("forged_secure");
  const fs::path security = test::make_security_folder(dir.path() / "sec", dir.path());

  auto plain = test::start_pipeline("synth", dataset, dir.path(), "plain", domain);
  ASSERT_EQ(test::finish(*plain), 0) << plain->err();

  auto secure = test::start_pipeline("synth", dataset, dir.path(), "secure", domain, {"security=" + security.string()});
  const pid_t recorder = wait_for_child(secure->pid(), "heslam-recorder");
  ASSERT_NE(recorder, 0) << secure->err();
  std::vector<std::unique_ptr<test::ChildProcess>> forgers;
  for (const char* mode : {"forge-odometry", "forge-frame-done", "forge-keyframe-done"}) {
    forgers.push_back(start_forger(dir.path(), mode, domain, secure->pid()));
  }
  forgers.push_back(
      start_forger(dir.path(), "forge-status", domain, secure->pid(), {"--pid", std::to_string(recorder)}));
  ASSERT_EQ(test::finish(*secure), 0) << secure->err();
  for (const auto& forger : forgers) {
    EXPECT_EQ(forger->wait(std::chrono::milliseconds(0)), std::nullopt) << "a forger stopped: " << forger->err();
  }
  const std::string summary = last_line(secure->err());
  std::cout << "secure run with forgers: " << summary << "\n";
  EXPECT_NE(summary.find("pipeline finished: tracked " + std::to_string(kFrames) + "/" + std::to_string(kFrames) +
                         " frames, 0 lost"),
            std::string::npos)
      << summary;
  EXPECT_EQ(summary.find("/forged/path.txt"), std::string::npos) << summary;
  const eval::Trajectory plain_poses = eval::read_trajectory(dir.path() / "plain.txt");
  const eval::Trajectory secure_poses = eval::read_trajectory(dir.path() / "secure.txt");
  ASSERT_EQ(plain_poses.size(), static_cast<std::size_t>(kFrames));
  ASSERT_EQ(secure_poses.size(), plain_poses.size());
  for (std::size_t i = 0; i < plain_poses.size(); ++i) {
    EXPECT_DOUBLE_EQ(secure_poses.stamps_s[i], plain_poses.stamps_s[i]);
    // Lockstep runs are repeatable to the last digit written; 1 um leaves room for text rounding only.
    EXPECT_LT((secure_poses.poses_wc[i].translation() - plain_poses.poses_wc[i].translation()).norm(), 1e-6) << i;
  }
}

}  // namespace
}  // namespace heslam

// Two supervisors sharing one pipeline file (hosts: groups, --host), here on one machine over
// loopback so it runs without root: start order across the two through the status topic, remote
// components never started or failed here, and the run ending on both sides (docs/deployment.md).
// The real two-host test over network namespaces is tests/multihost.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>

#include "child_process.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

using namespace std::chrono_literals;

// Bounds for a broken build; a healthy run needs a fraction of each.
constexpr auto kRunBound = 60s;

class SupervisorHosts : public ::testing::Test {
 protected:
  // Host a runs first and last (last ends the run after exit_after_s), host b runs middle.
  std::filesystem::path write_pipeline(const std::string& extra = "", const std::string& middle_config = "",
                                       const std::string& last_fields = "") {
    std::ofstream(dir_.path() / "last.yaml") << "exit_after_s: 2\n";
    if (!middle_config.empty()) std::ofstream(dir_.path() / "middle.yaml") << middle_config;
    const auto file = dir_.path() / "p.yaml";
    std::ofstream(file) << "name: hosts\ndomain: " << test::exclusive_domain_id() << "\nnamespace: h" << getpid()
                        << "\nstop_timeout_s: 3\n"
                        << extra
                        << "hosts:\n  a: \"first, last\"\n  b: middle\n"
                           "components:\n"
                           "  - {name: first, executable: heslam-test-talker}\n"
                           "  - {name: middle, executable: heslam-test-talker"
                        << (middle_config.empty() ? "" : ", config: middle.yaml")
                        << "}\n"
                           "  - {name: last, executable: heslam-test-talker, config: last.yaml, on_exit: shutdown"
                        << last_fields << "}\n";
    return file;
  }
  std::unique_ptr<test::ChildProcess> start(const std::filesystem::path& file, const std::string& host) {
    return std::make_unique<test::ChildProcess>(
        test::bin_dir() / "heslam-supervisor",
        std::vector<std::string>{file.string(), "--host", host, "--log-dir", (dir_.path() / ("logs_" + host)).string()},
        dir_.path(), "supervisor_" + host);
  }
  static std::size_t at(const std::string& text, const std::string& what) {
    const auto position = text.find(what);
    EXPECT_NE(position, std::string::npos) << "missing '" << what << "' in:\n" << text;
    return position;
  }
  test::ScratchDir dir_{"supervisor_hosts"};
};

TEST_F(SupervisorHosts, StartOrderHoldsAcrossHostsAndTheRunEndsOnBoth) {
  const auto file = write_pipeline();
  auto b = start(file, "b");  // started first: it waits for host a's "first"
  auto a = start(file, "a");
  ASSERT_EQ(a->wait(kRunBound), 0) << a->err();
  ASSERT_EQ(b->wait(kRunBound), 0) << b->err();
  const std::string a_err = a->err(), b_err = b->err();
  // a: first, then middle from host b, then last.
  EXPECT_LT(at(a_err, "started first"), at(a_err, "middle (another host) is ready"));
  EXPECT_LT(at(a_err, "middle (another host) is ready"), at(a_err, "started last"));
  EXPECT_EQ(a_err.find("started middle"), std::string::npos);
  // b: waited for first, ran middle, did not wait for last (it comes after), ended with a.
  EXPECT_LT(at(b_err, "first (another host) is ready"), at(b_err, "started middle"));
  EXPECT_EQ(b_err.find("started first"), std::string::npos);
  at(b_err, "the supervisor on host a is ending the run; stopping here too");
  at(b_err, "pipeline finished (ended by another host)");
  at(a_err, "info: pipeline finished");
}

// after: [] does not skip another host's component: that host may start much later than this one.
TEST_F(SupervisorHosts, AnotherHostsComponentGatesTheOnesAfterItEvenWithAfter) {
  const auto file = write_pipeline("", "", ", after: []");
  auto b = start(file, "b");
  auto a = start(file, "a");
  ASSERT_EQ(a->wait(kRunBound), 0) << a->err();
  ASSERT_EQ(b->wait(kRunBound), 0) << b->err();
  const std::string a_err = a->err();
  EXPECT_LT(at(a_err, "middle (another host) is ready"), at(a_err, "started last"));
}

TEST_F(SupervisorHosts, AnotherHostsFailureIsNotFailedHere) {
  // middle (host b) fails: b exits 1 and ends the run; a stops too but its own components were fine.
  const auto file = write_pipeline("", "exit_after_s: 1\nexit_code: 3\n");
  auto b = start(file, "b");
  auto a = start(file, "a");
  const auto b_code = b->wait(kRunBound);
  const auto a_code = a->wait(kRunBound);
  EXPECT_EQ(b_code, 1) << b->err();
  EXPECT_EQ(a_code, 0) << a->err();
  at(a->err(), "the supervisor on host b is ending the run (pipeline failed: middle exit code 3");
}

TEST_F(SupervisorHosts, AMissingHostIsWaitedForBoundedThenTheRunGoesOn) {
  const auto file = write_pipeline("remote_ready_timeout_s: 1\n");
  auto a = start(file, "a");  // host b never comes
  ASSERT_EQ(a->wait(kRunBound), 0) << a->err();
  at(a->err(), "middle: no RUNNING status from another host within 1 s; starting the next components anyway");
  at(a->err(), "started last");
}

// The issue-39 hang: a run with --only (its replay started by hand, outside any supervisor) waited
// for ever after the replay ended. The component that ends the run (on_exit: shutdown), run by hand,
// now ends it with its SHUTTING_DOWN status, as its exit would under the supervisor.
TEST_F(SupervisorHosts, AnEndingComponentStartedByHandEndsTheRun) {
  const auto file = write_pipeline();  // 'last' by hand runs until stopped: its last.yaml is not used
  auto supervisor = std::make_unique<test::ChildProcess>(
      test::bin_dir() / "heslam-supervisor",
      std::vector<std::string>{file.string(), "--only", "first,middle", "--log-dir", (dir_.path() / "logs").string()},
      dir_.path(), "supervisor_only");
  // Started once the supervisor listens for it (a status is volatile: one written before is not seen).
  const auto listening_by = std::chrono::steady_clock::now() + kRunBound;
  while (supervisor->err().find("waiting for last on another host") == std::string::npos &&
         std::chrono::steady_clock::now() < listening_by && !supervisor->wait(std::chrono::milliseconds(50))) {
  }
  ASSERT_NE(supervisor->err().find("waiting for last on another host"), std::string::npos) << supervisor->err();
  std::string ns = "h";  // write_pipeline's namespace (built in two steps: GCC 12 misreads "h" + string)
  ns += std::to_string(getpid());
  test::ChildProcess last(
      test::bin_dir() / "heslam-test-talker",
      {"--domain", std::to_string(test::exclusive_domain_id()), "--namespace", ns, "--name", "last"}, dir_.path(),
      "last_by_hand");
  const auto ready_by = std::chrono::steady_clock::now() + kRunBound;
  while (supervisor->err().find("last (another host) is ready") == std::string::npos &&
         std::chrono::steady_clock::now() < ready_by && !supervisor->wait(std::chrono::milliseconds(50))) {
  }
  ASSERT_NE(supervisor->err().find("last (another host) is ready"), std::string::npos) << supervisor->err();
  last.signal(SIGTERM);  // ends cleanly, as a replay at its last frame (SHUTTING_DOWN, exit 0)
  ASSERT_EQ(last.wait(kRunBound), 0) << last.err();
  ASSERT_EQ(supervisor->wait(kRunBound), 0) << supervisor->err();
  const std::string err = supervisor->err();
  at(err, "this host runs first, middle; elsewhere: last");
  at(err, "last, which ends the run (on_exit: shutdown), ended outside this supervisor; stopping");
  at(err, "info: pipeline finished (last ended outside this supervisor)");
}

}  // namespace
}  // namespace heslam

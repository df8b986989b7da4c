// Two supervisors sharing one pipeline file (hosts: groups, --host), here on one machine over
// loopback so it runs without root: start order across the two through the status topic, remote
// components never started or failed here, and the run ending on both sides (docs/deployment.md).
// The real two-host test over network namespaces is tests/multihost.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
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
  std::filesystem::path write_pipeline(const std::string& extra = "", const std::string& middle_config = "") {
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
                           "  - {name: last, executable: heslam-test-talker, config: last.yaml, on_exit: shutdown}\n";
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

}  // namespace
}  // namespace heslam

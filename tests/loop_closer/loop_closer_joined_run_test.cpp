// A loop closer started by hand into a running pipeline (HESLAM_RUN_ID, docs/loop_closer.md) ends
// with the run it joined: when the run's supervisor ends the run, and when the supervisor is killed.
// Its start line claims lockstep only when a pipeline file started it (issue 39). Real processes: a
// supervisor running a talker as the "pipeline", on a domain of this test's own.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <regex>
#include <string>
#include <thread>

#include "child_process.hpp"
#include "test_support.hpp"

namespace heslam {
namespace {

using namespace std::chrono_literals;

// Bounds for a broken build or a hung process; a healthy run needs a fraction of each.
constexpr auto kBound = 60s;

class LoopCloserJoinedRun : public ::testing::Test {
 protected:
  void start_run() {
    const auto file = dir_.path() / "p.yaml";
    std::ofstream(file) << "name: joined\ndomain: " << test::exclusive_domain_id() << "\nnamespace: j" << getpid()
                        << "\nstop_timeout_s: 3\ncomponents:\n  - {name: anchor, executable: heslam-test-talker}\n";
    supervisor_ = std::make_unique<test::ChildProcess>(
        test::bin_dir() / "heslam-supervisor",
        std::vector<std::string>{file.string(), "--log-dir", (dir_.path() / "logs").string(), "--no-progress"},
        dir_.path(), "supervisor");
    ASSERT_TRUE(wait_for(*supervisor_, "anchor is ready")) << supervisor_->err();
    static const std::regex run_line(R"(, run ([0-9]+:[0-9]+);)");
    std::smatch match;
    const std::string err = supervisor_->err();
    ASSERT_TRUE(std::regex_search(err, match, run_line)) << err;
    setenv("HESLAM_RUN_ID", match[1].str().c_str(), 1);
    std::string ns = "j";  // the pipeline's namespace (two steps: GCC 12 misreads "j" + string)
    ns += std::to_string(getpid());
    loop_closer_ = std::make_unique<test::ChildProcess>(
        test::bin_dir() / "heslam-loop-closer-proximity",
        std::vector<std::string>{"--domain", std::to_string(test::exclusive_domain_id()), "--namespace", ns},
        dir_.path(), "loop_closer_by_hand");
    unsetenv("HESLAM_RUN_ID");
    ASSERT_TRUE(wait_for(*loop_closer_, "detector ")) << loop_closer_->err();
    // The run's end counts once the loop closer has seen the run's supervisor (its status).
    ASSERT_TRUE(wait_for(*loop_closer_, "joined run " + match[1].str() + " of supervisor: exits when it ends"))
        << loop_closer_->err();
  }
  // Whether `text` appears in the child's output within `bound` (false at once if it exits without).
  static bool wait_for(test::ChildProcess& child, const std::string& text, std::chrono::seconds bound = kBound) {
    const auto until = std::chrono::steady_clock::now() + bound;
    while (std::chrono::steady_clock::now() < until) {
      if (!text.empty() && (child.err() + child.out()).find(text) != std::string::npos) return true;
      if (child.wait(std::chrono::milliseconds(50))) return (child.err() + child.out()).find(text) != std::string::npos;
    }
    return false;
  }
  test::ScratchDir dir_{"loop_closer_joined"};
  std::unique_ptr<test::ChildProcess> supervisor_;
  std::unique_ptr<test::ChildProcess> loop_closer_;
};

TEST_F(LoopCloserJoinedRun, ExitsWhenTheRunItJoinedEnds) {
  start_run();
  const std::string start = loop_closer_->err() + loop_closer_->out();
  // Joined by hand, it cannot know the run's mode: it says what it does instead of claiming lockstep.
  EXPECT_NE(start.find("global BA on (inline, each keyframe waits for it; --real-time for a real-time run)"),
            std::string::npos)
      << start;
  EXPECT_EQ(start.find("(lockstep)"), std::string::npos) << start;
  supervisor_->signal(SIGINT);  // the user stops the run
  ASSERT_EQ(supervisor_->wait(kBound), 0) << supervisor_->err();
  ASSERT_EQ(loop_closer_->wait(kBound), 0) << loop_closer_->err();
  EXPECT_NE((loop_closer_->err() + loop_closer_->out()).find("the supervisor (supervisor) is ending the run"),
            std::string::npos)
      << loop_closer_->err();
}

TEST_F(LoopCloserJoinedRun, ExitsWhenTheRunsSupervisorIsKilled) {
  start_run();
  supervisor_->signal(SIGKILL);  // its talker dies with it (PR_SET_PDEATHSIG); its writers' lease expires
  ASSERT_TRUE(supervisor_->wait(kBound).has_value());
  ASSERT_EQ(loop_closer_->wait(kBound), 0) << loop_closer_->err();
  EXPECT_NE((loop_closer_->err() + loop_closer_->out()).find("the supervisor (supervisor) is gone"), std::string::npos)
      << loop_closer_->err();
}

}  // namespace
}  // namespace heslam

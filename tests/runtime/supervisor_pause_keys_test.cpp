// Space on the supervisor's terminal pauses and resumes the pipeline's replay (pausable: true), as
// heslam-replay's own keyboard does when it runs by hand (issue 39). The supervisor runs on a pseudo
// terminal of its own (forkpty), so the test types on it as a user would; real processes, a domain of
// this test's own, every wait bounded.
#include <gtest/gtest.h>

#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace heslam {
namespace {

using namespace std::chrono_literals;

// Bound for a broken build or a hung process; the 95-frame clip needs about 19 s of replay at rate
// 0.25, slow enough that the second space finds it still playing however loaded the machine is.
constexpr auto kBound = 90s;

class PtySupervisor {
 public:
  explicit PtySupervisor(std::vector<std::string> args) {
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_ = forkpty(&master_, nullptr, nullptr, nullptr);
    if (pid_ == 0) {
      execv(argv[0], argv.data());
      _exit(127);
    }
  }
  ~PtySupervisor() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    if (master_ >= 0) close(master_);
  }
  bool started() const { return pid_ > 0; }
  // Reads the terminal until `text` appeared at or after `from` (true) or the process ended / the
  // bound passed (false).
  bool wait_for(const std::string& text, std::size_t from = 0) {
    const auto until = std::chrono::steady_clock::now() + kBound;
    while (output_.find(text, from) == std::string::npos) {
      if (std::chrono::steady_clock::now() >= until || !read_some())
        return output_.find(text, from) != std::string::npos;
    }
    return true;
  }
  std::size_t mark() const { return output_.size(); }
  void type(const std::string& keys) { ASSERT_EQ(write(master_, keys.data(), keys.size()), ssize_t(keys.size())); }
  // Reads until the process ends (bounded); its exit code, or -1.
  int finish() {
    const auto until = std::chrono::steady_clock::now() + kBound;
    while (std::chrono::steady_clock::now() < until) {
      read_some();
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        while (read_some()) {
        }
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
    }
    return -1;
  }
  const std::string& output() const { return output_; }

 private:
  // False once the terminal has nothing more (the process ended and its output was read).
  bool read_some() {
    pollfd input{master_, POLLIN, 0};
    if (poll(&input, 1, 100) <= 0) return true;
    char buffer[4096];
    const ssize_t n = read(master_, buffer, sizeof buffer);
    if (n <= 0) return false;
    output_.append(buffer, static_cast<std::size_t>(n));
    return true;
  }
  pid_t pid_ = -1;
  int master_ = -1;
  bool exited_ = false;
  std::string output_;
};

TEST(SupervisorPauseKeys, SpaceResumesAndPausesTheReplay) {
  const auto dataset = test::shared_dataset("euroc_v101_head");
  if (dataset.empty()) GTEST_SKIP() << "../shared/data/euroc_v101_head is absent";
  test::ScratchDir dir("supervisor_pause_keys");
  PtySupervisor supervisor({(test::bin_dir() / "heslam-supervisor").string(),
                            (test::source_dir() / "config/pipelines/replay_spy.yaml").string(), "--domain",
                            std::to_string(test::exclusive_domain_id()), "--no-progress", "--log-dir",
                            (dir.path() / "logs").string(), "--arg", "dataset=" + dataset.string(), "--arg",
                            "start_paused=on", "--arg", "rate=0.25"});
  ASSERT_TRUE(supervisor.started());
  ASSERT_TRUE(supervisor.wait_for("space on this terminal resumes and pauses replay (it starts paused)"))
      << supervisor.output();
  ASSERT_TRUE(supervisor.wait_for("replay is ready")) << supervisor.output();
  // Paused from the start: nothing is published until the first space.
  EXPECT_EQ(supervisor.output().find("frames published"), std::string::npos) << supervisor.output();
  std::size_t typed = supervisor.mark();
  supervisor.type(" ");
  ASSERT_TRUE(supervisor.wait_for("resumed replay", typed)) << supervisor.output();
  ASSERT_TRUE(supervisor.wait_for("replay | [replay] info: resumed", typed)) << supervisor.output();
  typed = supervisor.mark();
  supervisor.type(" ");
  ASSERT_TRUE(supervisor.wait_for("paused replay (space resumes)", typed)) << supervisor.output();
  ASSERT_TRUE(supervisor.wait_for("replay | [replay] info: paused", typed)) << supervisor.output();
  supervisor.type(" ");
  ASSERT_TRUE(supervisor.wait_for("pipeline finished: 95 of 95 frames published")) << supervisor.output();
  EXPECT_EQ(supervisor.finish(), 0) << supervisor.output();
}

}  // namespace
}  // namespace heslam

// heslam-supervisor end to end: real processes (heslam-test-talker) on the test's own DDS domain.
// Every wait is bounded; every process started is killed in TearDown whatever happened.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include <gtest/gtest.h>

#include "runtime/participant.hpp"
#include "runtime/reader.hpp"
#include "runtime/sequence.hpp"
#include "runtime/topics.hpp"
#include "test_domain.hpp"
#include "test_support.hpp"

namespace heslam::test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// Bounds for a broken build; a healthy run needs a fraction of each.
constexpr auto kStartupBound = 20s;
constexpr auto kExitBound = 20s;

bool process_alive(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  if (!stat) return false;
  std::string text((std::istreambuf_iterator<char>(stat)), {});
  const auto close = text.rfind(')');
  return close != std::string::npos && close + 2 < text.size() && text[close + 2] != 'Z';
}

class SupervisorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("heslam_supervisor_test_" + std::to_string(getpid()) + "_" +
                                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }

  void TearDown() override {
    if (supervisor_pid_ > 0) {
      kill(supervisor_pid_, SIGKILL);
      waitpid(supervisor_pid_, nullptr, 0);
    }
    for (pid_t pid : children()) kill(pid, SIGKILL);
    std::filesystem::remove_all(dir_);
  }

  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }

  // A pipeline on this test's domain; components is the YAML list body.
  std::string pipeline(const std::string& components, const std::string& extra = "") {
    return "name: test\ndomain: " + std::to_string(test_domain_id()) + "\nnamespace: t" + std::to_string(getpid()) +
           "\nstop_timeout_s: 3\n" + extra + "components:\n" + components;
  }

  pid_t spawn_supervisor(std::vector<std::string> args, const std::string& output_name = "supervisor.out") {
    return spawn(bin_dir() / "heslam-supervisor", std::move(args), output_name);
  }

  // `program` with `args`, its stdout and stderr into dir_/output_name.
  pid_t spawn(const std::filesystem::path& program, std::vector<std::string> args, const std::string& output_name) {
    args.insert(args.begin(), program.string());
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    const std::string out = (dir_ / output_name).string();
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    pid_t pid = 0;
    EXPECT_EQ(posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    return pid;
  }

  void start(const std::string& pipeline_text) {
    write("pipeline.yaml", pipeline_text);
    supervisor_pid_ = spawn_supervisor({(dir_ / "pipeline.yaml").string(), "--log-dir", (dir_ / "logs").string()});
  }

  std::string output(const std::string& name = "supervisor.out") const {
    std::ifstream in(dir_ / name);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  }

  // Waits for the exit of another supervisor than the test's main one; its exit code or -1.
  static int wait_exit_of(pid_t pid, std::chrono::milliseconds bound) {
    const auto deadline = Clock::now() + bound;
    while (Clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      std::this_thread::sleep_for(10ms);
    }
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
    return -1;
  }

  // Polls the supervisor's output for a regex until bound.
  bool wait_for_output(const std::string& pattern, std::chrono::milliseconds bound,
                       const std::string& name = "supervisor.out") const {
    const std::regex re(pattern);
    const auto deadline = Clock::now() + bound;
    while (Clock::now() < deadline) {
      if (std::regex_search(output(name), re)) return true;
      std::this_thread::sleep_for(10ms);
    }
    return false;
  }

  // Pids the supervisor reported starting ("started NAME (pid N)"), for one name or all.
  std::vector<pid_t> started_pids(const std::string& name = "[A-Za-z0-9_-]+") const {
    const std::regex re("info: started " + name + " \\(pid ([0-9]+)\\)");
    const std::string text = output();
    std::vector<pid_t> pids;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator(); ++it) {
      pids.push_back(std::stoi((*it)[1].str()));
    }
    return pids;
  }
  std::set<pid_t> children() const {
    const auto pids = started_pids();
    return {pids.begin(), pids.end()};
  }

  // Waits for the supervisor's exit; returns its exit code, or -1 on timeout / signal.
  int wait_exit(std::chrono::milliseconds bound) {
    const auto deadline = Clock::now() + bound;
    while (Clock::now() < deadline) {
      int status = 0;
      if (waitpid(supervisor_pid_, &status, WNOHANG) == supervisor_pid_) {
        supervisor_pid_ = 0;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(10ms);
    }
    return -1;
  }

  bool all_children_gone(std::chrono::milliseconds bound) const {
    const auto deadline = Clock::now() + bound;
    while (Clock::now() < deadline) {
      bool any = false;
      for (pid_t pid : children()) any = any || process_alive(pid);
      if (!any) return true;
      std::this_thread::sleep_for(10ms);
    }
    return false;
  }

  std::filesystem::path dir_;
  pid_t supervisor_pid_ = 0;
};

constexpr const char* kTalker = "  - name: talker\n    executable: heslam-test-talker\n";

TEST_F(SupervisorTest, RestartsAComponentKilledWithSigkillAfterItsRestartDelay) {
  runtime::Participant participant(runtime::ParticipantOptions{test_domain_id(), ""});
  runtime::Reader<msg::ComponentStatus> status_reader(participant,
                                                      runtime::Topics("t" + std::to_string(getpid())).status());
  start(pipeline(std::string(kTalker) + "    restart: on-failure\n"));
  ASSERT_TRUE(wait_for_output("talker is ready", kStartupBound)) << output();
  const pid_t first = started_pids("talker").at(0);
  ASSERT_EQ(kill(first, SIGKILL), 0);
  const auto killed_at = Clock::now();
  // The restart requirement is a new talker within 1 s of the kill: the supervisor plans it
  // 0.1 s after the death (asserted below). How long the kernel takes to report the death and start
  // the new process on a loaded machine is speed: printed, not asserted.
  bool restarted = false;
  while (Clock::now() - killed_at < kStartupBound && !restarted) {
    const auto pids = started_pids("talker");
    restarted = pids.size() == 2 && process_alive(pids[1]);
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_TRUE(restarted) << output();
  std::printf("[ figures  ] talker restarted %.0f ms after its SIGKILL (requirement: < 1000 ms on an idle machine)\n",
              std::chrono::duration<double, std::milli>(Clock::now() - killed_at).count());
  EXPECT_TRUE(wait_for_output(
      "talker \\(pid " + std::to_string(first) + "\\) killed by SIGKILL; restarting in 0.1 s \\(restart 1 of 3\\)",
      kStartupBound))
      << output();
  EXPECT_TRUE(wait_for_output("restarted talker", kStartupBound)) << output();

  // The restart is also reported on the status topic: the supervisor's counter restarts.talker.
  bool reported = false;
  const auto deadline = Clock::now() + kStartupBound;
  while (!reported && Clock::now() < deadline) {
    for (auto& received : status_reader.take()) {
      if (!received.info.valid_data || runtime::to_string(received.sample->name) != "supervisor") continue;
      for (const auto& counter : runtime::view(received.sample->counters)) {
        reported = reported || (runtime::to_string(counter.name) == "restarts.talker" && counter.value == 1);
      }
    }
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_TRUE(reported);

  kill(supervisor_pid_, SIGTERM);
  EXPECT_EQ(wait_exit(kExitBound), 0) << output();
  EXPECT_TRUE(all_children_gone(kExitBound));
}

TEST_F(SupervisorTest, SigtermStopsEverythingInReverseOrder) {
  start(
      pipeline("  - name: first\n    executable: heslam-test-talker\n"
               "  - name: second\n    executable: heslam-test-talker\n"));
  ASSERT_TRUE(wait_for_output("second is ready", kStartupBound)) << output();
  kill(supervisor_pid_, SIGTERM);
  EXPECT_EQ(wait_exit(kExitBound), 0) << output();
  EXPECT_TRUE(all_children_gone(kExitBound));
  const std::string text = output();
  const auto second_stopped = text.find("second stopped");
  const auto first_stopped = text.find("first stopped");
  ASSERT_NE(second_stopped, std::string::npos) << text;
  ASSERT_NE(first_stopped, std::string::npos) << text;
  EXPECT_LT(second_stopped, first_stopped);
  // Output is forwarded with a prefix and written to a log per component.
  EXPECT_NE(text.find("second | [second] info: shutting down"), std::string::npos) << text;
  std::ifstream log(dir_ / "logs" / "first.log");
  const std::string log_text((std::istreambuf_iterator<char>(log)), {});
  EXPECT_NE(log_text.find("[first] info: shutting down"), std::string::npos);
}

TEST_F(SupervisorTest, KilledSupervisorLeavesNoOrphans) {
  start(
      pipeline("  - name: first\n    executable: heslam-test-talker\n"
               "  - name: other\n    executable: /bin/sleep\n    args: [\"600\"]\n"
               "    common_args: false\n    ready: started\n"));
  ASSERT_TRUE(wait_for_output("started other", kStartupBound)) << output();
  ASSERT_TRUE(wait_for_output("first is ready", kStartupBound)) << output();
  kill(supervisor_pid_, SIGKILL);
  waitpid(supervisor_pid_, nullptr, 0);
  supervisor_pid_ = 0;
  // PR_SET_PDEATHSIG (set by the exec trampoline) ends even a program that knows nothing of heslam.
  EXPECT_TRUE(all_children_gone(kExitBound)) << output();
}

// nice: N lowers the component's priority (all its threads: set before exec) by N relative to the
// supervisor's own; other components keep the supervisor's.
TEST_F(SupervisorTest, NiceLowersTheComponentsPriority) {
  start(
      pipeline("  - name: background\n    executable: /bin/sleep\n    args: [\"600\"]\n"
               "    common_args: false\n    ready: started\n    nice: 7\n"
               "  - name: foreground\n    executable: /bin/sleep\n    args: [\"600\"]\n"
               "    common_args: false\n    ready: started\n"));
  ASSERT_TRUE(wait_for_output("started foreground", kStartupBound)) << output();
  EXPECT_TRUE(wait_for_output("started background \\(pid [0-9]+\\), nice \\+7", kStartupBound)) << output();
  // Field 19 of /proc/PID/stat is the niceness; the process may still be the trampoline for a moment.
  auto niceness = [](pid_t pid) {
    std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
    std::string text((std::istreambuf_iterator<char>(stat)), {});
    std::istringstream fields(text.substr(text.rfind(')') + 2));
    std::string field;
    for (int i = 3; i <= 19; ++i) fields >> field;
    return std::stoi(field);
  };
  const int own = niceness(getpid());  // the supervisor inherits the test's niceness
  ASSERT_EQ(started_pids("background").size(), 1u);
  ASSERT_EQ(started_pids("foreground").size(), 1u);
  const pid_t background = started_pids("background")[0];
  const auto deadline = Clock::now() + kStartupBound;
  while (niceness(background) != std::min(own + 7, 19) && Clock::now() < deadline) std::this_thread::sleep_for(10ms);
  EXPECT_EQ(niceness(background), std::min(own + 7, 19));
  EXPECT_EQ(niceness(started_pids("foreground")[0]), own);
}

// Killed at stop, a component did not finish its shutdown work (the recorder's final files, the
// mapper's map): the run is not a success.
TEST_F(SupervisorTest, ComponentIgnoringSigtermIsKilledAndFailsTheRun) {
  write("stubborn.yaml", "ignore_sigterm: true\n");
  start(pipeline(std::string(kTalker) + "    config: stubborn.yaml\n"));
  ASSERT_TRUE(wait_for_output("talker is ready", kStartupBound)) << output();
  kill(supervisor_pid_, SIGTERM);
  EXPECT_EQ(wait_exit(kExitBound), 1) << output();
  EXPECT_NE(output().find("talker did not stop within 3 s; sending SIGKILL"), std::string::npos) << output();
  EXPECT_NE(output().find("pipeline failed: talker did not stop within 3 s and was killed"), std::string::npos)
      << output();
  EXPECT_TRUE(all_children_gone(kExitBound));
}

// A component's own stop_timeout_s overrides the pipeline's (3 s here): 1 s for this one.
TEST_F(SupervisorTest, ComponentStopTimeoutOverridesThePipelines) {
  write("stubborn.yaml", "ignore_sigterm: true\n");
  start(pipeline(std::string(kTalker) + "    config: stubborn.yaml\n    stop_timeout_s: 1\n"));
  ASSERT_TRUE(wait_for_output("talker is ready", kStartupBound)) << output();
  kill(supervisor_pid_, SIGTERM);
  EXPECT_EQ(wait_exit(kExitBound), 1) << output();
  EXPECT_NE(output().find("talker did not stop within 1 s; sending SIGKILL"), std::string::npos) << output();
  EXPECT_NE(output().find("pipeline failed: talker did not stop within 1 s and was killed"), std::string::npos)
      << output();
  EXPECT_TRUE(all_children_gone(kExitBound));
}

TEST_F(SupervisorTest, RequiredComponentFailureFailsTheRun) {
  write("fail.yaml", "exit_after_s: 0.2\nexit_code: 3\n");
  start(pipeline(std::string(kTalker) + "    config: fail.yaml\n" +
                 "  - name: bystander\n    executable: heslam-test-talker\n"));
  EXPECT_EQ(wait_exit(kExitBound), 1) << output();
  EXPECT_NE(output().find("exit code 3"), std::string::npos) << output();
  EXPECT_TRUE(all_children_gone(kExitBound));
}

TEST_F(SupervisorTest, GivesUpAfterMaxRestarts) {
  write("fail.yaml", "exit_after_s: 0.1\nexit_code: 1\n");
  start(pipeline(std::string(kTalker) + "    config: fail.yaml\n    restart: on-failure\n    max_restarts: 2\n"
                                        "    restart_backoff_s: 0.05\n"));
  EXPECT_EQ(wait_exit(kExitBound), 1) << output();
  EXPECT_NE(output().find("giving up after 2 restarts"), std::string::npos) << output();
  EXPECT_EQ(started_pids("talker").size(), 3u);
}

// An error a restart cannot fix (a bad config, a missing input, an unwritable output) is
// not retried: the component said "starting" on the handshake pipe but never "running". One try,
// its one-line reason in the supervisor's last line, exit 1. (Before: 1 + max_restarts tries.)
TEST_F(SupervisorTest, StartupErrorIsNotRestarted) {
  write("bad.yaml", "exit_code: 300\n");
  start(
      pipeline(std::string(kTalker) + "    config: bad.yaml\n    restart: on-failure\n    restart_backoff_s: 0.05\n"));
  EXPECT_EQ(wait_exit(kExitBound), 1) << output();
  EXPECT_EQ(started_pids("talker").size(), 1u) << output();
  const std::string text = output();
  EXPECT_NE(text.find("not restarted: a restart cannot fix a start-up error"), std::string::npos) << text;
  // The last line says which component failed and why.
  std::string last;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) last = line;
  EXPECT_EQ(last, "[supervisor] error: pipeline failed: talker failed at start-up (exit code 1): heslam-test-talker: " +
                      (dir_ / "bad.yaml").string() + ": field 'exit_code': expected an integer in [0, 255], got 300")
      << text;
}

// after: [] starts a component with the supervisor, without waiting for the one before it; a
// component after others starts once they are all ready. Without it, one after the other.
TEST_F(SupervisorTest, AfterStartsIndependentComponentsTogether) {
  start(
      pipeline("  - name: first\n    executable: heslam-test-talker\n"
               "  - name: second\n    executable: heslam-test-talker\n    after: []\n"
               "  - name: third\n    executable: heslam-test-talker\n    after: [first, second]\n"
               "  - name: fourth\n    executable: heslam-test-talker\n"));
  ASSERT_TRUE(wait_for_output("fourth is ready", kStartupBound)) << output();
  kill(supervisor_pid_, SIGTERM);
  EXPECT_EQ(wait_exit(kExitBound), 0) << output();
  const std::string text = output();
  const auto at = [&](const std::string& line) {
    const auto position = text.find(line);
    EXPECT_NE(position, std::string::npos) << line << " in:\n" << text;
    return position;
  };
  EXPECT_LT(at("started second"), at("first is ready"));
  EXPECT_LT(at("first is ready"), at("started third"));
  EXPECT_LT(at("second is ready"), at("started third"));
  EXPECT_LT(at("third is ready"), at("started fourth"));
}

// A start-up error of a component started together with others fails the run as it would alone;
// the others are stopped.
TEST_F(SupervisorTest, StartupErrorOfAComponentStartedTogetherFailsTheRun) {
  write("bad.yaml", "exit_code: 300\n");
  start(
      pipeline("  - name: good\n    executable: heslam-test-talker\n"
               "  - name: bad\n    executable: heslam-test-talker\n    after: []\n    config: bad.yaml\n"
               "    restart: on-failure\n"));
  EXPECT_EQ(wait_exit(kExitBound), 1) << output();
  EXPECT_TRUE(all_children_gone(kExitBound));
  EXPECT_EQ(started_pids("bad").size(), 1u) << output();
  const std::string text = output();
  std::string last;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) last = line;
  EXPECT_EQ(last, "[supervisor] error: pipeline failed: bad failed at start-up (exit code 1): heslam-test-talker: " +
                      (dir_ / "bad.yaml").string() + ": field 'exit_code': expected an integer in [0, 255], got 300")
      << text;
}

// A crash after start-up is still restarted (the handshake said "running").
TEST_F(SupervisorTest, FailureAfterStartupIsStillRestarted) {
  write("fail.yaml", "exit_after_s: 0.1\nexit_code: 1\n");
  start(pipeline(std::string(kTalker) + "    config: fail.yaml\n    restart: on-failure\n    max_restarts: 1\n"
                                        "    restart_backoff_s: 0.05\n"));
  EXPECT_EQ(wait_exit(kExitBound), 1) << output();
  EXPECT_EQ(started_pids("talker").size(), 2u) << output();
  EXPECT_EQ(output().find("failed at start-up"), std::string::npos) << output();
}

// A component stopped with SIGSTOP (a debugger, Ctrl-Z, a stalled machine) still stops cleanly:
// the supervisor resumes it half-way to the stop timeout. Before: SIGTERM stayed pending until the
// timeout, then SIGKILL, and a finished run ended with exit code 1 ("did not stop within 3 s").
TEST_F(SupervisorTest, StoppedComponentIsResumedAndStopsCleanly) {
  start(pipeline(kTalker));
  ASSERT_TRUE(wait_for_output("talker is ready", kStartupBound)) << output();
  const std::vector<pid_t> pids = started_pids("talker");
  ASSERT_EQ(pids.size(), 1u);
  ASSERT_EQ(kill(pids.front(), SIGSTOP), 0);
  kill(supervisor_pid_, SIGTERM);
  EXPECT_EQ(wait_exit(kExitBound), 0) << output();
  EXPECT_NE(output().find("talker is stopped (SIGSTOP or a debugger); resuming it (SIGCONT) so that it stops"),
            std::string::npos)
      << output();
  EXPECT_NE(output().find("talker stopped"), std::string::npos) << output();
  EXPECT_EQ(output().find("did not stop"), std::string::npos) << output();
}

// A restarted component that fails at its own start-up fails the run mid-run, and the last line
// says so. Before: "talker failed at start-up", as if the run had never started.
TEST_F(SupervisorTest, RestartFailingAtItsStartUpIsAMidRunFailure) {
  write("talker.yaml", "exit_after_s: 1\nexit_code: 1\n");
  start(pipeline(std::string(kTalker) + "    config: talker.yaml\n    restart: on-failure\n    max_restarts: 10\n"
                                        "    restart_backoff_s: 0.3\n    restart_backoff_max_s: 0.3\n"));
  ASSERT_TRUE(wait_for_output("talker is ready", kStartupBound)) << output();
  write("talker.yaml", "exit_code: 300\n");  // what the next restart reads: a start-up error
  EXPECT_EQ(wait_exit(kExitBound), 1) << output();
  // Which restart it is depends on how fast the machine made the first one ready.
  EXPECT_TRUE(std::regex_search(
      last_line(output()), std::regex(R"(^\[supervisor\] error: pipeline failed: talker failed mid-run: restart \d+ )"
                                      R"(failed at its start-up \(exit code 1\): heslam-test-talker: )")))
      << output();
  EXPECT_GE(started_pids("talker").size(), 2u) << output();
}

// One run per domain: a second supervisor of the same domain and namespace is refused with one line
// naming the run it found, before it starts anything; --domain auto picks a free domain instead.
// Before: both ran, each reading the other's samples.
TEST_F(SupervisorTest, SecondRunOnTheSameDomainIsRefusedAndDomainAutoPicksAFreeOne) {
  start(pipeline(kTalker));
  ASSERT_TRUE(wait_for_output("talker is ready", kStartupBound)) << output();
  const pid_t second =
      spawn_supervisor({(dir_ / "pipeline.yaml").string(), "--log-dir", (dir_ / "logs2").string()}, "second.out");
  EXPECT_EQ(wait_exit_of(second, kExitBound), 1) << output("second.out");
  const std::string refused = output("second.out");
  EXPECT_NE(refused.find("domain " + std::to_string(test_domain_id()) + ", namespace 't" + std::to_string(getpid()) +
                         "' is in use by another heslam run on this host (supervisor pid " +
                         std::to_string(supervisor_pid_) + ")"),
            std::string::npos)
      << refused;
  EXPECT_EQ(refused.find("started talker"), std::string::npos) << refused;

  const pid_t automatic = spawn_supervisor(
      {(dir_ / "pipeline.yaml").string(), "--domain", "auto", "--log-dir", (dir_ / "logs3").string()}, "auto.out");
  ASSERT_TRUE(wait_for_output("talker is ready", kStartupBound, "auto.out")) << output("auto.out");
  const std::string text = output("auto.out");
  std::smatch match;
  ASSERT_TRUE(std::regex_search(text, match, std::regex("pipeline 'test' on domain ([0-9]+)"))) << text;
  EXPECT_NE(std::stoi(match[1].str()), test_domain_id()) << text;
  kill(automatic, SIGTERM);
  EXPECT_EQ(wait_exit_of(automatic, kExitBound), 0) << output("auto.out");
  kill(supervisor_pid_, SIGTERM);
  EXPECT_EQ(wait_exit(kExitBound), 0) << output();
}

// Another run's writer on the domain (here a talker started by hand with a data writer: another run
// id; a status-only observer such as a viewer does not count) that appears
// mid-run is reported, and the run's last line says its results are its own; a supervisor started
// while it is alive is refused (the DDS check: no supervisor of this host holds the domain).
TEST_F(SupervisorTest, AnotherRunAppearingMidRunIsReportedAndRefusesNewRuns) {
  start(pipeline(kTalker));
  ASSERT_TRUE(wait_for_output("talker is ready", kStartupBound)) << output();
  std::ofstream(dir_ / "stray.yaml") << "%YAML:1.0\n---\ndata_writer: true\n";
  const pid_t stray =
      spawn(bin_dir() / "heslam-test-talker",
            {"--domain", std::to_string(test_domain_id()), "--namespace", "t" + std::to_string(getpid()), "--name",
             "stray", "--config", (dir_ / "stray.yaml").string()},
            "stray.out");
  ASSERT_GT(stray, 0);
  EXPECT_TRUE(wait_for_output("another heslam run appeared on domain", kStartupBound)) << output();
  kill(supervisor_pid_, SIGTERM);
  EXPECT_EQ(wait_exit(kExitBound), 0) << output();
  EXPECT_NE(
      last_line(output()).find("another heslam run appeared on the domain (run " + std::to_string(getpid()) + ":"),
      std::string::npos)
      << output();

  const pid_t second =
      spawn_supervisor({(dir_ / "pipeline.yaml").string(), "--log-dir", (dir_ / "logs2").string()}, "second.out");
  EXPECT_EQ(wait_exit_of(second, kExitBound), 1) << output("second.out");
  EXPECT_NE(output("second.out").find("is in use by another heslam run: run " + std::to_string(getpid()) + ":"),
            std::string::npos)
      << output("second.out");
  EXPECT_EQ(output("second.out").find("started talker"), std::string::npos) << output("second.out");
  kill(stray, SIGKILL);
  waitpid(stray, nullptr, 0);
}

// The test suite reserves its domains: not only against other test processes (their locks) but also
// against a pipeline started by hand on this host (its supervisor's claim). Before: a test took a
// domain a hand-started run was using and failed on that run's samples (Recovery.SoakRandomKills on
// a loaded CI machine).
TEST(TestDomains, ADomainAHeslamRunHoldsIsNotReserved) {
  const int wanted = 100 + static_cast<int>(getpid() % 100);
  const auto claims = std::filesystem::temp_directory_path() / "heslam-domains";
  std::filesystem::create_directories(claims);
  const auto claim_file = claims / (std::to_string(wanted) + "-handrun" + std::to_string(getpid()) + ".lock");
  const int fd = ::open(claim_file.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);  // what a running supervisor holds
  EXPECT_TRUE(supervisor_on_domain(wanted));
  EXPECT_NE(reserve_test_domain(wanted - 1), wanted);  // `wanted` is the first id it would try
  close(fd);
  std::filesystem::remove(claim_file);
  EXPECT_FALSE(supervisor_on_domain(wanted));
}

TEST_F(SupervisorTest, OnExitShutdownEndsTheRunCleanly) {
  write("short.yaml", "exit_after_s: 0.3\n");
  start(
      pipeline("  - name: service\n    executable: heslam-test-talker\n"
               "  - name: job\n    executable: heslam-test-talker\n    config: short.yaml\n    on_exit: shutdown\n"));
  EXPECT_EQ(wait_exit(kExitBound), 0) << output();
  EXPECT_NE(output().find("job finished (exit code 0)"), std::string::npos) << output();
  EXPECT_NE(output().find("service stopped"), std::string::npos) << output();
  EXPECT_TRUE(all_children_gone(kExitBound));
}

// A component's bad config or arguments: exit 1 with one line, before it starts running.
class ComponentErrors : public SupervisorTest {
 protected:
  std::pair<int, std::string> run_talker(std::vector<std::string> args) {
    args.insert(args.begin(), (bin_dir() / "heslam-test-talker").string());
    args.insert(args.end(), {"--domain", std::to_string(test_domain_id())});
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    const std::string out = (dir_ / "talker.out").string();
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    EXPECT_EQ(posix_spawn(&supervisor_pid_, argv[0], &actions, nullptr, argv.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    const int code = wait_exit(kExitBound);
    std::ifstream in(out);
    return {code, std::string((std::istreambuf_iterator<char>(in)), {})};
  }
};

TEST_F(ComponentErrors, BadFieldValue) {
  write("bad.yaml", "exit_code: 300\n");
  const auto [code, text] = run_talker({"--config", (dir_ / "bad.yaml").string()});
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-test-talker: " + (dir_ / "bad.yaml").string() +
                      ": field 'exit_code': expected an integer in [0, 255], got 300\n");
}

TEST_F(ComponentErrors, UnknownField) {
  write("typo.yaml", "exit_afer_s: 1\n");
  const auto [code, text] = run_talker({"--config", (dir_ / "typo.yaml").string()});
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-test-talker: " + (dir_ / "typo.yaml").string() +
                      ": unknown field 'exit_afer_s' (no such option)\n");
}

TEST_F(ComponentErrors, MissingConfigAndBadFlags) {
  auto [code, text] = run_talker({"--config", (dir_ / "none.yaml").string()});
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-test-talker: " + (dir_ / "none.yaml").string() + ": cannot open\n");
  std::tie(code, text) = run_talker({"stray"});
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-test-talker: unexpected argument 'stray' (see --help)\n");
  std::tie(code, text) = run_talker({"--log-level", "loud"});
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-test-talker: --log-level: expected debug, info, warn, error or off, got 'loud'\n");
}

// --check: a broken pipeline file gives its one-line message and exit code 1; nothing starts.
class SupervisorCheck : public SupervisorTest {
 protected:
  std::pair<int, std::string> check(const std::string& text, std::vector<std::string> extra = {}) {
    write("pipeline.yaml", text);
    std::vector<std::string> args{(dir_ / "pipeline.yaml").string(), "--check"};
    args.insert(args.end(), extra.begin(), extra.end());
    supervisor_pid_ = spawn_supervisor(args);
    const int code = wait_exit(kExitBound);
    return {code, output()};
  }
  std::string file() const { return (dir_ / "pipeline.yaml").string(); }
};

// A missing input (the dataset) is caught by --check and before anything starts.
TEST_F(SupervisorCheck, RejectsAMissingOrEmptyInput) {
  const std::string component = std::string(kTalker) + "    inputs: [\"$(arg dataset)\"]\n";
  const std::string text = pipeline(component, "args:\n  dataset: \"\"\n");
  const std::string missing = (dir_ / "no_such_dataset").string();
  auto [code, out] = check(text, {"--arg", "dataset=" + missing});
  EXPECT_EQ(code, 1);
  EXPECT_EQ(out, "heslam-supervisor: " + file() + ": component 'talker': input " + missing + " does not exist\n");
  std::tie(code, out) = check(text);
  EXPECT_EQ(code, 1);
  EXPECT_EQ(out,
            "heslam-supervisor: " + file() +
                ": component 'talker': input '$(arg dataset)' is empty (give it with --arg, e.g. --arg dataset=DIR)\n");
  std::tie(code, out) = check(text, {"--arg", "dataset=" + dir_.string()});
  EXPECT_EQ(code, 0) << out;
  // A run fails the same way, starting nothing.
  write("pipeline.yaml", text);
  supervisor_pid_ = spawn_supervisor({file(), "--arg", "dataset=" + missing});
  EXPECT_EQ(wait_exit(kExitBound), 1);
  EXPECT_TRUE(started_pids().empty()) << output();
}

TEST_F(SupervisorCheck, AcceptsAGoodFile) {
  write("talker.yaml", "exit_after_s: 1\n");
  const auto [code, text] = check(pipeline(std::string(kTalker) + "    config: talker.yaml\n"));
  EXPECT_EQ(code, 0) << text;
  EXPECT_EQ(text, file() + ": OK (1 components: talker)\n");
}

TEST_F(SupervisorCheck, RejectsBadYaml) {
  const auto [code, text] = check("components: [\n");
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text.rfind("heslam-supervisor: " + file() + ": not valid YAML: line 1", 0), 0u) << text;
}

TEST_F(SupervisorCheck, RejectsUnknownExecutable) {
  const auto [code, text] = check(pipeline("  - name: x\n    executable: heslam-no-such-tool\n"));
  EXPECT_EQ(code, 1);
  EXPECT_NE(text.find(file() + ": component 'x': executable 'heslam-no-such-tool' not found"), std::string::npos)
      << text;
}

TEST_F(SupervisorCheck, RejectsDuplicateNames) {
  const auto [code, text] = check(pipeline(std::string(kTalker) + kTalker));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-supervisor: " + file() + ": components[1]: duplicate name 'talker' (also components[0])\n");
}

TEST_F(SupervisorCheck, RejectsAnAfterThatIsNotAnEarlierComponent) {
  const auto [code, text] = check(
      pipeline(std::string(kTalker) + "    after: [later]\n  - name: later\n    executable: heslam-test-talker\n"));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-supervisor: " + file() +
                      ": component 'talker': field 'after': 'later' is not a component before it in the file "
                      "(components start in file order)\n");
}

TEST_F(SupervisorCheck, RejectsMissingConfig) {
  const auto [code, text] = check(pipeline(std::string(kTalker) + "    config: missing.yaml\n"));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-supervisor: " + file() + ": component 'talker': config " + (dir_ / "missing.yaml").string() +
                      " does not exist\n");
}

TEST_F(SupervisorCheck, RejectsBrokenComponentConfig) {
  write("broken.yaml", "a: [1,\n");
  const auto [code, text] = check(pipeline(std::string(kTalker) + "    config: broken.yaml\n"));
  EXPECT_EQ(code, 1);
  EXPECT_NE(text.find((dir_ / "broken.yaml").string() + ": not valid YAML: line 1"), std::string::npos) << text;
}

TEST_F(SupervisorCheck, RejectsUnknownArg) {
  const auto [code, text] =
      check(pipeline(std::string(kTalker) + "    args: [\"$(arg dataset)\"]\n", "args:\n  rate: 1\n"));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text,
            "heslam-supervisor: " + file() + ": field 'components[0].args': unknown $(arg dataset) (declared: rate)\n");
}

TEST_F(SupervisorCheck, ArgOverridesAreSubstitutedAndUndeclaredOnesRejected) {
  auto [code, text] = check(pipeline(std::string(kTalker) + "    args: [\"$(arg mode)\"]\n", "args:\n  mode: a\n"),
                            {"--arg", "mode=b"});
  EXPECT_EQ(code, 0) << text;
  std::tie(code, text) = check(pipeline(std::string(kTalker), "args:\n  mode: a\n"), {"--arg", "speed=2"});
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-supervisor: " + file() +
                      ": --arg speed: the pipeline declares no such argument (declared: mode)\n");
}

TEST_F(SupervisorCheck, RejectsANegativeNice) {
  const auto [code, text] = check(pipeline(std::string(kTalker) + "    nice: -5\n"));
  EXPECT_EQ(code, 1);
  EXPECT_NE(text.find("components[0].nice"), std::string::npos) << text;
}

TEST_F(SupervisorCheck, RejectsUnknownFieldsAndBadValues) {
  const auto [code, text] = check(pipeline(std::string(kTalker) + "    restart: sometimes\n    restrat: always\n"));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(text, "heslam-supervisor: " + file() +
                      ": field 'components[0].restart': expected one of never on-failure always, got 'sometimes'\n"
                      "heslam-supervisor: " +
                      file() + ": unknown field 'components[0].restrat' (no such option)\n");
}

// The pipeline's name names the log folder: a huge or unprintable one is refused by --check with a
// short line. Before: a 10 MB name passed --check and the run printed one 10 MB error line; a
// non-UTF-8 byte went raw into a folder name.
TEST_F(SupervisorCheck, RejectsAHugeOrUnprintablePipelineNameWithAShortLine) {
  const std::string huge(10 * 1024 * 1024, 'n');
  std::string text = pipeline(kTalker);
  text.replace(text.find("name: test"), 10, "name: " + huge);
  auto [code, out] = check(text);
  EXPECT_EQ(code, 1);
  EXPECT_LT(out.size(), 400u) << out.substr(0, 400);
  EXPECT_NE(
      out.find("field 'name': expected 1-64 letters, digits, '_', '-' or '.' (it names the log folder), got 'nnn"),
      std::string::npos)
      << out.substr(0, 400);
  EXPECT_NE(out.find("... (10485760 bytes)"), std::string::npos) << out.substr(0, 400);

  text = pipeline(kTalker);
  text.replace(text.find("name: test"), 10, std::string("name: te\xFF") + "st");
  std::tie(code, out) = check(text);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("field 'name'"), std::string::npos) << out;
  EXPECT_NE(out.find("got 'te\\xFFst'"), std::string::npos) << out;
  EXPECT_EQ(out.find('\xFF'), std::string::npos) << out;
}

// Arguments may default to each other, resolved in order; a cycle is one line naming it. Before:
// --check passed and the run failed later with an unrelated error.
TEST_F(SupervisorCheck, ArgumentsReferringToEachOtherAreResolvedAndACycleIsRefused) {
  auto [code, out] = check(pipeline(std::string(kTalker) + "    args: [\"--log-level\", \"$(arg level)\"]\n",
                                    "args:\n  level: \"$(arg default_level)\"\n  default_level: warn\n"));
  EXPECT_EQ(code, 0) << out;
  std::tie(code, out) = check(
      pipeline(std::string(kTalker) + "    args: [\"$(arg a)\"]\n", "args:\n  a: \"x$(arg b)\"\n  b: \"$(arg a)\"\n"));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(out, "heslam-supervisor: " + file() +
                     ": argument 'a': the arguments refer to each other in a cycle (a -> b -> a)\n");
}

// --check runs each heslam program's own check of its arguments: what a run would refuse, --check
// refuses, with the program's one line. Before: exit code 0, and the run failed.
TEST_F(SupervisorCheck, RunsEachProgramsOwnCheckOfItsArguments) {
  const auto [code, out] = check(pipeline(std::string(kTalker) + "    args: [\"--log-level\", \"loud\"]\n"));
  EXPECT_EQ(code, 1);
  EXPECT_EQ(out,
            "heslam-supervisor: pipeline.yaml: component 'talker': heslam-test-talker: --log-level: expected debug, "
            "info, warn, error or off, got 'loud'\n");
}

}  // namespace
}  // namespace heslam::test

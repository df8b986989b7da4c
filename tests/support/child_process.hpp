// A child process for integration tests: spawned with its output in files, waited for with a
// bound, and always killed and reaped when the test ends (no stray processes on failure).
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace heslam::test {

class ChildProcess {
 public:
  // Starts program with args; stdout and stderr go to files beside each other in `log_dir`.
  ChildProcess(const std::filesystem::path& program, const std::vector<std::string>& args,
               const std::filesystem::path& log_dir, const std::string& label)
      : stdout_path_(log_dir / (label + ".out")), stderr_path_(log_dir / (label + ".err")) {
    std::vector<std::string> all{program.string()};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& arg : all) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, stderr_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int error = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (error != 0) throw std::runtime_error("cannot start " + program.string());
  }
  ~ChildProcess() {
    if (pid_ > 0 && !exit_code_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // The exit code (128 + signal when killed), or nullopt if still running after timeout.
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!exit_code_) {
      int status = 0;
      const pid_t done = waitpid(pid_, &status, WNOHANG);
      if (done == pid_) {
        exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        break;
      }
      if (std::chrono::steady_clock::now() >= deadline) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return exit_code_;
  }

  void signal(int number) const {
    if (!exit_code_) kill(pid_, number);
  }

  std::string out() const { return read(stdout_path_); }
  std::string err() const { return read(stderr_path_); }
  pid_t pid() const { return pid_; }

 private:
  static std::string read(const std::filesystem::path& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

  std::filesystem::path stdout_path_;
  std::filesystem::path stderr_path_;
  pid_t pid_ = 0;
  std::optional<int> exit_code_;
};

// Runs `program` to its end, bounded by `timeout`: its exit code, -1 when it did not end in time.
// `output`, when given: its stderr, then its stdout.
inline int run_to_end(const std::filesystem::path& program, const std::vector<std::string>& args,
                      const std::filesystem::path& dir, const std::string& label, std::chrono::seconds timeout,
                      std::string* output = nullptr) {
  ChildProcess child(program, args, dir, label);
  const std::optional<int> code = child.wait(timeout);
  if (output != nullptr) *output = child.err() + child.out();
  return code.value_or(-1);
}

}  // namespace heslam::test

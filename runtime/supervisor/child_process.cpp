// Spawning (posix_spawn, own process group, clean signal state), output pipes, the exec trampoline.
#include "runtime/supervisor/child_process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <utility>

#include "runtime/startup_notify.hpp"

extern char** environ;

namespace heslam::supervisor {
namespace {

// Read size per call: a component's log burst fits in one or two reads.
constexpr std::size_t kReadChunk = 64 * 1024;
// The child's descriptor of the handshake pipe: the first one after stdin, stdout, stderr.
constexpr int kChildNotifyFd = 3;
// Tells the trampoline the niceness increment; removed from the environment before exec.
constexpr const char* kNiceVariable = "HESLAM_CHILD_NICE";

void close_fd(int& fd) {
  if (fd >= 0) close(fd);
  fd = -1;
}

}  // namespace

ChildProcess ChildProcess::spawn(const std::filesystem::path& trampoline, const std::filesystem::path& program,
                                 const std::vector<std::string>& args, const std::map<std::string, std::string>& env,
                                 int nice_increment) {
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) {
    throw std::runtime_error("cannot start " + program.string() + ": pipe: " + std::strerror(errno));
  }
  int notify_fds[2];
  if (pipe2(notify_fds, O_CLOEXEC) != 0) {
    close(pipe_fds[0]);
    close(pipe_fds[1]);
    throw std::runtime_error("cannot start " + program.string() + ": pipe: " + std::strerror(errno));
  }

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDERR_FILENO);
  posix_spawn_file_actions_adddup2(&actions, notify_fds[1], kChildNotifyFd);  // dup2 clears close-on-exec

  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  posix_spawnattr_setpgroup(&attributes, 0);  // own group: Ctrl-C reaches only the supervisor
  sigset_t empty_mask, defaults;
  sigemptyset(&empty_mask);
  posix_spawnattr_setsigmask(&attributes, &empty_mask);
  sigemptyset(&defaults);
  for (int s : {SIGINT, SIGTERM, SIGPIPE, SIGCHLD, SIGHUP, SIGUSR1, SIGUSR2}) sigaddset(&defaults, s);
  posix_spawnattr_setsigdefault(&attributes, &defaults);

  std::vector<std::string> argv_text{trampoline.string(), "--exec-child", program.string()};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& text : argv_text) argv.push_back(text.data());
  argv.push_back(nullptr);

  std::map<std::string, std::string> environment;
  for (char** entry = environ; *entry != nullptr; ++entry) {
    const std::string text = *entry;
    const auto eq = text.find('=');
    if (eq != std::string::npos) environment[text.substr(0, eq)] = text.substr(eq + 1);
  }
  for (const auto& [key, value] : env) environment[key] = value;
  environment["HESLAM_SUPERVISOR_PID"] = std::to_string(getpid());
  environment[runtime::kNotifyFdVariable] = std::to_string(kChildNotifyFd);
  environment.erase(kNiceVariable);
  if (nice_increment > 0) environment[kNiceVariable] = std::to_string(nice_increment);
  std::vector<std::string> env_text;
  for (const auto& [key, value] : environment) env_text.push_back(key + "=" + value);
  std::vector<char*> envp;
  for (auto& text : env_text) envp.push_back(text.data());
  envp.push_back(nullptr);

  pid_t pid = 0;
  const int error = posix_spawn(&pid, trampoline.c_str(), &actions, &attributes, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  close(pipe_fds[1]);
  close(notify_fds[1]);
  if (error != 0) {
    close(pipe_fds[0]);
    close(notify_fds[0]);
    throw std::runtime_error("cannot start " + program.string() + ": " + std::strerror(error));
  }
  fcntl(pipe_fds[0], F_SETFL, fcntl(pipe_fds[0], F_GETFL) | O_NONBLOCK);
  fcntl(notify_fds[0], F_SETFL, fcntl(notify_fds[0], F_GETFL) | O_NONBLOCK);
  ChildProcess child;
  child.pid_ = pid;
  child.output_fd_ = pipe_fds[0];
  child.notify_fd_ = notify_fds[0];
  return child;
}

ChildProcess::ChildProcess(ChildProcess&& other) noexcept { *this = std::move(other); }

ChildProcess& ChildProcess::operator=(ChildProcess&& other) noexcept {
  if (this != &other) {
    close_output();
    close_fd(notify_fd_);
    pid_ = std::exchange(other.pid_, 0);
    output_fd_ = std::exchange(other.output_fd_, -1);
    notify_fd_ = std::exchange(other.notify_fd_, -1);
    said_starting_ = std::exchange(other.said_starting_, false);
    said_running_ = std::exchange(other.said_running_, false);
    said_shutting_down_ = std::exchange(other.said_shutting_down_, false);
    partial_ = std::move(other.partial_);
    notify_partial_ = std::move(other.notify_partial_);
    pending_result_ = std::exchange(other.pending_result_, Result{});
    result_ = std::exchange(other.result_, std::nullopt);
    participants_ = std::exchange(other.participants_, {});
  }
  return *this;
}

ChildProcess::~ChildProcess() {
  close_output();
  close_fd(notify_fd_);
}

void ChildProcess::close_output() { close_fd(output_fd_); }

void ChildProcess::read_notifications() {
  char buffer[256];
  while (notify_fd_ >= 0) {
    const ssize_t n = read(notify_fd_, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    if (n <= 0) {
      close_fd(notify_fd_);  // the program closed it (after its result) or ended
      return;
    }
    notify_partial_.append(buffer, static_cast<std::size_t>(n));
    for (std::size_t newline; (newline = notify_partial_.find('\n')) != std::string::npos;) {
      const std::string line = notify_partial_.substr(0, newline);
      notify_partial_.erase(0, newline + 1);
      if (line == runtime::kNotifyStarting) said_starting_ = true;
      if (line == runtime::kNotifyRunning) said_starting_ = said_running_ = true;
      if (line == runtime::kNotifyShuttingDown) said_shutting_down_ = true;
      const std::string participant_prefix = std::string(runtime::kNotifyParticipant) + " ";
      if (line.starts_with(participant_prefix)) participants_.insert(line.substr(participant_prefix.size()));
      read_result_line(line);
    }
  }
}

bool ChildProcess::stopped() const {
  if (pid_ <= 0) return false;
  std::ifstream stat("/proc/" + std::to_string(pid_) + "/stat");
  const std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  // The state follows the ')' closing the command name (proc(5)): T stopped, t tracing stop.
  const std::size_t close = text.rfind(')');
  return close != std::string::npos && close + 2 < text.size() && (text[close + 2] == 'T' || text[close + 2] == 't');
}

void ChildProcess::read_result_line(const std::string& line) {
  const std::string counter_prefix = std::string(runtime::kNotifyCounter) + " ";
  const std::string result_prefix = std::string(runtime::kNotifyResult) + " ";
  if (line.starts_with(counter_prefix)) {
    const std::size_t space = line.rfind(' ');
    if (space <= counter_prefix.size()) return;
    const std::string value = line.substr(space + 1);
    std::uint64_t number = 0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), number);
    if (error != std::errc{} || end != value.data() + value.size()) return;
    pending_result_.counters[line.substr(counter_prefix.size(), space - counter_prefix.size())] = number;
  } else if (line.starts_with(result_prefix)) {
    pending_result_.text = line.substr(result_prefix.size());
    result_ = std::move(pending_result_);
    pending_result_ = Result{};
  }
}

bool ChildProcess::read_lines(std::vector<std::string>& lines) {
  if (output_fd_ < 0) return false;
  char buffer[kReadChunk];
  for (;;) {
    const ssize_t n = read(output_fd_, buffer, sizeof buffer);
    if (n > 0) {
      partial_.append(buffer, static_cast<std::size_t>(n));
      std::size_t start = 0;
      for (std::size_t newline; (newline = partial_.find('\n', start)) != std::string::npos; start = newline + 1) {
        lines.push_back(partial_.substr(start, newline - start));
      }
      partial_.erase(0, start);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    // End of stream (every writer, including grandchildren, closed it) or an error.
    if (!partial_.empty()) lines.push_back(std::exchange(partial_, {}));
    close_output();
    return false;
  }
}

void ChildProcess::signal_group(int signal_number) const {
  if (pid_ > 0) kill(-pid_, signal_number);
}

void exec_child(int argc, char** argv) {
  // argv: heslam-supervisor --exec-child PROGRAM ARGS...
  if (argc < 3) {
    const char message[] = "heslam-supervisor: --exec-child needs a program\n";
    [[maybe_unused]] const ssize_t ignored = write(STDERR_FILENO, message, sizeof message - 1);
    _exit(127);
  }
  prctl(PR_SET_PDEATHSIG, SIGTERM);
  // If the supervisor died before the prctl, nobody will signal us: do not start at all.
  const char* parent = std::getenv("HESLAM_SUPERVISOR_PID");
  if (parent != nullptr && std::to_string(getppid()) != parent) _exit(127);
  // Before exec: Linux niceness is per thread, and threads inherit their creator's.
  if (const char* increment = std::getenv(kNiceVariable); increment != nullptr) {
    errno = 0;
    if (nice(std::atoi(increment)) == -1 && errno != 0) {
      const std::string message = std::string("heslam-supervisor: cannot lower the priority of ") + argv[2] + ": " +
                                  std::strerror(errno) + "\n";
      [[maybe_unused]] const ssize_t ignored = write(STDERR_FILENO, message.data(), message.size());
    }
    unsetenv(kNiceVariable);
  }
  std::vector<char*> args;
  std::string name = std::filesystem::path(argv[2]).filename().string();
  args.push_back(name.data());
  for (int i = 3; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  execv(argv[2], args.data());
  const std::string message =
      std::string("heslam-supervisor: cannot execute ") + argv[2] + ": " + std::strerror(errno) + "\n";
  [[maybe_unused]] const ssize_t ignored = write(STDERR_FILENO, message.data(), message.size());
  _exit(127);
}

std::string describe_exit(int wait_status) {
  if (WIFEXITED(wait_status)) return "exit code " + std::to_string(WEXITSTATUS(wait_status));
  if (WIFSIGNALED(wait_status)) {
    const int s = WTERMSIG(wait_status);
    const char* name = sigabbrev_np(s);
    return std::string("killed by ") + (name != nullptr ? std::string("SIG") + name : "signal " + std::to_string(s));
  }
  return "stopped";
}

}  // namespace heslam::supervisor

// The child side of the handshake with heslam-supervisor (see startup_notify.hpp).
#include "runtime/startup_notify.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <string>

namespace heslam::runtime {
namespace {

std::mutex g_mutex;
int g_fd = -2;  // -2: not looked up yet, -1: none or closed
bool g_running_sent = false;

// Takes the descriptor from the environment once; keeps it from our own children.
int notify_fd_locked() {
  if (g_fd != -2) return g_fd;
  g_fd = -1;
  const char* text = std::getenv(kNotifyFdVariable);
  if (text == nullptr || *text == '\0') return g_fd;
  const int fd = std::atoi(text);
  unsetenv(kNotifyFdVariable);
  if (fd < 3 || fcntl(fd, F_GETFD) < 0) return g_fd;
  fcntl(fd, F_SETFD, FD_CLOEXEC);
  g_fd = fd;
  return g_fd;
}

void write_line(int fd, const char* text) {
  const std::string line = std::string(text) + "\n";
  // A pipe write this small is atomic; a dead supervisor (EPIPE, SIGPIPE ignored) does not matter.
  [[maybe_unused]] const ssize_t ignored = ::write(fd, line.data(), line.size());
}

}  // namespace

void notify_supervisor_starting() {
  std::lock_guard lock(g_mutex);
  const int fd = notify_fd_locked();
  if (fd >= 0 && !g_running_sent) write_line(fd, kNotifyStarting);
}

void notify_supervisor_running() {
  std::lock_guard lock(g_mutex);
  const int fd = notify_fd_locked();
  if (fd < 0 || g_running_sent) return;
  write_line(fd, kNotifyRunning);
  g_running_sent = true;
}

void notify_supervisor_participant(const std::string& guid_prefix) {
  std::lock_guard lock(g_mutex);
  const int fd = notify_fd_locked();
  if (fd >= 0) write_line(fd, (std::string(kNotifyParticipant) + " " + guid_prefix).c_str());
}

void notify_supervisor_result(const std::map<std::string, std::uint64_t>& counters, const std::string& result,
                              bool ended_cleanly) {
  std::lock_guard lock(g_mutex);
  const int fd = notify_fd_locked();
  if (fd < 0) return;
  // Never blocks (the pipe holds 64 KB; these lines are a few KB): a stopped supervisor must not
  // hold up a program's exit.
  fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
  if (ended_cleanly) write_line(fd, kNotifyShuttingDown);
  for (const auto& [name, value] : counters) {
    // Counter names are identifiers; one with a space or newline could not be read back.
    if (name.find_first_of(" \n") != std::string::npos) continue;
    write_line(fd, (std::string(kNotifyCounter) + " " + name + " " + std::to_string(value)).c_str());
  }
  std::string line = result.substr(0, kMaxResultBytes);
  std::replace(line.begin(), line.end(), '\n', ' ');
  write_line(fd, (std::string(kNotifyResult) + " " + line).c_str());
  ::close(fd);
  g_fd = -1;
}

}  // namespace heslam::runtime

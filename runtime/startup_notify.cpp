// The child side of the start-up handshake (see startup_notify.hpp).
#include "runtime/startup_notify.hpp"

#include <fcntl.h>
#include <unistd.h>

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
  ::close(fd);
  g_fd = -1;
}

}  // namespace heslam::runtime

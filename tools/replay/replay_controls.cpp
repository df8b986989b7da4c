// Keyboard and signal controls of heslam-replay.
#include "tools/replay/replay_controls.hpp"

#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <csignal>

namespace heslam {

namespace {

// Signal handlers may only touch lock-free atomics.
std::atomic<int> g_pause_requests{0};
std::atomic<int> g_resume_requests{0};

extern "C" void on_pause_signal(int) { g_pause_requests.fetch_add(1, std::memory_order_relaxed); }
extern "C" void on_resume_signal(int) { g_resume_requests.fetch_add(1, std::memory_order_relaxed); }

constexpr char kPauseKey = ' ';
constexpr char kQuitKey = 'q';

}  // namespace

ReplayControls::ReplayControls(bool keyboard) {
  struct sigaction action {};
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  action.sa_handler = on_pause_signal;
  sigaction(SIGUSR1, &action, nullptr);
  action.sa_handler = on_resume_signal;
  sigaction(SIGUSR2, &action, nullptr);

  // Only a foreground terminal: a background job reading stdin would be stopped by SIGTTIN.
  if (keyboard && isatty(STDIN_FILENO) && tcgetpgrp(STDIN_FILENO) == getpgrp() &&
      tcgetattr(STDIN_FILENO, &saved_terminal_) == 0) {
    termios raw = saved_terminal_;
    raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);
    raw.c_cc[VMIN] = 0;
    raw.c_cc[VTIME] = 0;
    keyboard_active_ = tcsetattr(STDIN_FILENO, TCSANOW, &raw) == 0;
  }
}

ReplayControls::~ReplayControls() {
  if (keyboard_active_) tcsetattr(STDIN_FILENO, TCSANOW, &saved_terminal_);
  signal(SIGUSR1, SIG_DFL);
  signal(SIGUSR2, SIG_DFL);
}

std::vector<ReplayControl> ReplayControls::poll() {
  std::vector<ReplayControl> controls;
  for (int n = g_pause_requests.exchange(0); n > 0; --n) controls.push_back(ReplayControl::kPause);
  for (int n = g_resume_requests.exchange(0); n > 0; --n) controls.push_back(ReplayControl::kResume);
  if (!keyboard_active_) return controls;
  pollfd input{STDIN_FILENO, POLLIN, 0};
  while (::poll(&input, 1, 0) > 0 && (input.revents & POLLIN)) {
    char key = 0;
    if (read(STDIN_FILENO, &key, 1) != 1) break;
    if (key == kPauseKey) controls.push_back(ReplayControl::kTogglePause);
    if (key == kQuitKey) controls.push_back(ReplayControl::kQuit);
  }
  return controls;
}

}  // namespace heslam

// Space on the supervisor's terminal (runtime/supervisor/pause_keys.hpp).
#include "runtime/supervisor/pause_keys.hpp"

#include <poll.h>
#include <unistd.h>

namespace heslam::supervisor {
namespace {

constexpr char kPauseKey = ' ';

}  // namespace

PauseKeys::PauseKeys(bool enabled) {
  // Only a foreground terminal: a background job reading stdin would be stopped by SIGTTIN.
  if (!enabled || !isatty(STDIN_FILENO) || tcgetpgrp(STDIN_FILENO) != getpgrp() ||
      tcgetattr(STDIN_FILENO, &saved_terminal_) != 0) {
    return;
  }
  termios raw = saved_terminal_;
  raw.c_lflag &= ~static_cast<tcflag_t>(ICANON | ECHO);  // ISIG stays: Ctrl-C still stops the run
  raw.c_cc[VMIN] = 0;
  raw.c_cc[VTIME] = 0;
  active_ = tcsetattr(STDIN_FILENO, TCSANOW, &raw) == 0;
}

PauseKeys::~PauseKeys() {
  if (active_) tcsetattr(STDIN_FILENO, TCSANOW, &saved_terminal_);
}

int PauseKeys::take_toggles() {
  if (!active_) return 0;
  int toggles = 0;
  pollfd input{STDIN_FILENO, POLLIN, 0};
  while (::poll(&input, 1, 0) > 0 && (input.revents & POLLIN)) {
    char key = 0;
    if (read(STDIN_FILENO, &key, 1) != 1) break;
    if (key == kPauseKey) ++toggles;
  }
  return toggles;
}

}  // namespace heslam::supervisor

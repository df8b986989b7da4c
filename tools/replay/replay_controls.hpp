// Pause/resume of a running replay: space (and q) on the terminal, SIGUSR1 (pause) / SIGUSR2
// (resume) from scripts and tests. The terminal is put in non-canonical, no-echo mode only while
// a ReplayControls lives, and restored by its destructor.
#pragma once

#include <termios.h>

#include <vector>

namespace heslam {

enum class ReplayControl { kPause, kResume, kTogglePause, kQuit };

class ReplayControls {
 public:
  // keyboard: read keys when stdin is a terminal. Signal handlers are installed either way.
  explicit ReplayControls(bool keyboard);
  ~ReplayControls();
  ReplayControls(const ReplayControls&) = delete;
  ReplayControls& operator=(const ReplayControls&) = delete;

  // What was asked since the last call, in order (never blocks).
  std::vector<ReplayControl> poll();

  bool keyboard_active() const { return keyboard_active_; }

 private:
  bool keyboard_active_ = false;
  termios saved_terminal_{};
};

}  // namespace heslam

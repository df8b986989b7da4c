// The supervisor's keyboard: space on its terminal pauses and resumes the pipeline's pausable
// components (`pausable: true`, e.g. the replay), as the replay's own keyboard would when run by hand.
// The terminal is put in non-canonical, no-echo mode (Ctrl-C still signals) only while a PauseKeys
// lives, and only when stdin is the foreground terminal; its destructor restores it.
#pragma once

#include <termios.h>

namespace heslam::supervisor {

class PauseKeys {
 public:
  explicit PauseKeys(bool enabled);
  ~PauseKeys();
  PauseKeys(const PauseKeys&) = delete;
  PauseKeys& operator=(const PauseKeys&) = delete;

  bool active() const { return active_; }
  // How many times space was pressed since the last call (never blocks); other keys are ignored.
  int take_toggles();

 private:
  bool active_ = false;
  termios saved_terminal_{};
};

}  // namespace heslam::supervisor

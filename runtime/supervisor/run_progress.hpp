// The supervisor's one progress line for a whole run: frames published / total, tracked, fps and ETA, from the
// components' status (the replay's frames_published / frames_total counters, the recorder's
// "tracked N/M frames" message). On a terminal it is redrawn in place; in a log file or pipe a plain
// line at every 10 % of the frames (the rule of heslam-synth's progress); nothing without a total.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

namespace heslam::supervisor {

struct RunCounts {
  std::optional<std::uint64_t> tracked;  // frames with a pose (the recorder's status); unset: no recorder
  std::uint64_t published = 0;           // frames the replay published (this pass)
  std::uint64_t total = 0;               // frames per pass; 0: unknown (a live camera)
  double fps = 0.0;                      // published frames per second; 0: not measured yet
};

// "published 42/160 frames   26%, 40 tracked  19.9 fps  ETA 5.9 s": the percent, fps and ETA count
// published frames, "tracked" the frames with a pose so far (without a recorder: no tracked count).
std::string format_run_progress(const RunCounts& counts);

// The tracked count of a recorder status message "tracked N/M frames, ...", nullopt for others.
std::optional<std::uint64_t> tracked_from_message(const std::string& message);

class RunProgress {
 public:
  enum class Mode { kLive, kPlain, kOff };
  using Clock = std::chrono::steady_clock;

  explicit RunProgress(Mode mode) : mode_(mode) {}
  Mode mode() const { return mode_; }

  // The line to show now, or nothing. kLive: the current line when it changed, at most every
  // kLiveRedrawPeriod; kPlain: a line when the run passes a new 10 % step (once per step; the first
  // at 10 %), none while the total is unknown.
  std::optional<std::string> update(const RunCounts& counts, Clock::time_point now);

 private:
  Mode mode_;
  std::string last_line_;
  Clock::time_point last_draw_{};
  int last_step_ = 0;  // plain: the 10 % steps already reported
};

}  // namespace heslam::supervisor

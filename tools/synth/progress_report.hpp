// heslam-synth's progress on stderr, written for whoever reads it: on a terminal one line redrawn in
// place; in a log file or pipe (not a terminal) a plain line every 10 % of the frames, so a log holds
// a few readable lines instead of every redraw piled into one; nothing with --quiet.
//
// API:
//   ProgressReport report(std::cerr, ProgressReport::mode_for(quiet, isatty(2)), "room");
//   report.update(done, total, elapsed_s);   // after each frame; decides itself whether to print
#pragma once

#include <ostream>
#include <string>

namespace heslam::synth {

class ProgressReport {
 public:
  enum class Mode {
    live,   // terminal: "\r" redraw, at most every kLiveRedrawPeriod_s, newline after the last frame
    steps,  // not a terminal: one line at each kStepPercent of the frames (and at the last frame)
    quiet,  // nothing
  };
  // A terminal cannot show more than ~10 redraws a second anyway.
  static constexpr double kLiveRedrawPeriod_s = 0.1;
  // 10 lines for a whole run: enough to see it advance and to estimate the remaining time.
  static constexpr int kStepPercent = 10;

  static Mode mode_for(bool quiet, bool stderr_is_terminal) {
    return quiet ? Mode::quiet : stderr_is_terminal ? Mode::live : Mode::steps;
  }

  ProgressReport(std::ostream& out, Mode mode, std::string label) : out_(out), mode_(mode), label_(std::move(label)) {}

  // `done` of `total` frames written after `elapsed_s` seconds.
  void update(int done, int total, double elapsed_s);

 private:
  std::string line(int done, int total, double elapsed_s) const;

  std::ostream& out_;
  Mode mode_;
  std::string label_;
  double last_redraw_s_ = -1.0;
  int last_step_ = 0;  // steps printed so far (each kStepPercent)
};

}  // namespace heslam::synth

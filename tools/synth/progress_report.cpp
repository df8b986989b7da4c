// heslam-synth's progress: live redraw on a terminal, a line per 10 % elsewhere.
#include "tools/synth/progress_report.hpp"

#include <cstdio>

namespace heslam::synth {

std::string ProgressReport::line(int done, int total, double elapsed_s) const {
  char text[256];
  const double percent = total > 0 ? 100.0 * done / total : 100.0;
  std::snprintf(text, sizeof text, "heslam-synth: %s %d/%d frames %3.0f%% (%.1f pairs/s)", label_.c_str(), done, total,
                percent, elapsed_s > 0 ? done / elapsed_s : 0.0);
  return text;
}

void ProgressReport::update(int done, int total, double elapsed_s) {
  const bool last = done >= total;
  switch (mode_) {
    case Mode::quiet: return;
    case Mode::live:
      if (!last && last_redraw_s_ >= 0.0 && elapsed_s - last_redraw_s_ < kLiveRedrawPeriod_s) return;
      last_redraw_s_ = elapsed_s;
      out_ << "\r\033[K" << line(done, total, elapsed_s) << (last ? "\n" : "") << std::flush;
      return;
    case Mode::steps: {
      // The number of whole steps reached; the last frame always reaches the last step.
      const int step = last ? 100 / kStepPercent : done * (100 / kStepPercent) / total;
      if (step <= last_step_) return;
      last_step_ = step;
      out_ << line(done, total, elapsed_s) << "\n" << std::flush;
      return;
    }
  }
}

}  // namespace heslam::synth

// Text and pacing of the supervisor's run progress line.
#include "runtime/supervisor/run_progress.hpp"

#include <cstdio>
#include <string_view>

namespace heslam::supervisor {

namespace {

using namespace std::chrono_literals;

// A terminal cannot show more; the status it is made from comes once a second anyway.
constexpr auto kLiveRedrawPeriod = 100ms;
// Plain lines: one per this many percent of the frames, so a log holds ten lines per run.
constexpr int kPlainStepPercent = 10;
constexpr std::string_view kTrackedPrefix = "tracked ";

}  // namespace

std::string format_run_progress(const RunCounts& counts) {
  const double fps = counts.fps;
  // The percent and the ETA count published frames; "tracked" (frames with a pose) stands apart.
  char tracked[48] = "";
  if (counts.tracked) {
    std::snprintf(tracked, sizeof tracked, ", %llu tracked", static_cast<unsigned long long>(*counts.tracked));
  }
  char line[200];
  if (counts.total == 0) {
    std::snprintf(line, sizeof line, "published %llu frames%s  %.1f fps",
                  static_cast<unsigned long long>(counts.published), tracked, fps);
    return line;
  }
  const double percent = 100.0 * static_cast<double>(counts.published) / static_cast<double>(counts.total);
  char eta[32] = "ETA -";
  if (fps > 0.0 && counts.total >= counts.published) {
    std::snprintf(eta, sizeof eta, "ETA %.1f s", static_cast<double>(counts.total - counts.published) / fps);
  }
  std::snprintf(line, sizeof line, "published %llu/%llu frames %4.0f%%%s  %.1f fps  %s",
                static_cast<unsigned long long>(counts.published), static_cast<unsigned long long>(counts.total),
                percent, tracked, fps, eta);
  return line;
}

std::optional<std::uint64_t> tracked_from_message(const std::string& message) {
  if (message.compare(0, kTrackedPrefix.size(), kTrackedPrefix) != 0) return std::nullopt;
  unsigned long long tracked = 0;
  char slash = 0;
  if (std::sscanf(message.c_str() + kTrackedPrefix.size(), "%llu%c", &tracked, &slash) != 2 || slash != '/') {
    return std::nullopt;
  }
  return tracked;
}

std::optional<std::string> RunProgress::update(const RunCounts& counts, Clock::time_point now) {
  if (mode_ == Mode::kOff || counts.published == 0) return std::nullopt;
  if (mode_ == Mode::kPlain) {
    if (counts.total == 0) return std::nullopt;
    const int step = static_cast<int>(100 * counts.published / counts.total) / kPlainStepPercent;
    if (step <= last_step_) return std::nullopt;
    last_step_ = step;
    return format_run_progress(counts);
  }
  std::string line = format_run_progress(counts);
  if (line == last_line_ || now - last_draw_ < kLiveRedrawPeriod) return std::nullopt;
  last_draw_ = now;
  last_line_ = line;
  return line;
}

}  // namespace heslam::supervisor

// Progress line and summary text of heslam-replay.
#include "tools/replay/replay_progress.hpp"

#include <cstdio>

namespace heslam {

namespace {

// Playing seconds (pauses excluded): fps and ETA describe the replay, not the user's coffee break.
double playing_s(const ReplayCounts& counts) { return counts.elapsed_s - counts.paused_s; }

double fps(const ReplayCounts& counts) {
  const double seconds = playing_s(counts);
  return seconds > 0.0 ? static_cast<double>(counts.published) / seconds : 0.0;
}

}  // namespace

std::string format_progress_line(const ReplayCounts& counts) {
  const double rate = fps(counts);
  const double percent =
      counts.total > 0 ? 100.0 * static_cast<double>(counts.pass_published) / static_cast<double>(counts.total) : 0.0;
  char eta[32] = "ETA -";
  if (rate > 0.0 && counts.total >= counts.pass_published) {
    std::snprintf(eta, sizeof(eta), "ETA %.1f s", static_cast<double>(counts.total - counts.pass_published) / rate);
  }
  char line[160];
  std::snprintf(line, sizeof(line), "frame %zu/%zu %4.0f%%  %.1f fps  %s", counts.pass_published, counts.total, percent,
                rate, eta);
  std::string text = line;
  if (counts.imu_readings > 0) text += "  imu " + std::to_string(counts.imu_readings);
  if (counts.pass > 1) text += "  pass " + std::to_string(counts.pass);
  if (counts.skipped_images > 0) text += "  skipped " + std::to_string(counts.skipped_images);
  if (counts.paused) text += "  [paused]";
  return text;
}

std::string format_summary(const ReplayCounts& counts) {
  char line[200];
  std::snprintf(line, sizeof(line), "published %zu frames in %.2f s (%.1f fps)", counts.published, playing_s(counts),
                fps(counts));
  std::string text = line;
  if (counts.pass > 1) text += " over " + std::to_string(counts.pass) + " passes";
  text += "; skipped " + std::to_string(counts.skipped_images) + " images";
  text += "; " + std::to_string(counts.unpaired_rows) + " unpaired rows";
  if (counts.imu_readings > 0) text += "; " + std::to_string(counts.imu_readings) + " IMU readings";
  return text;
}

std::string format_result(const ReplayCounts& counts, bool loop, bool stopped_early) {
  std::string text =
      loop ? "published " + std::to_string(counts.published) + " frames over " + std::to_string(counts.pass) +
                 (counts.pass == 1 ? " pass" : " passes")
           : std::to_string(counts.published) + " of " + std::to_string(counts.total) + " frames published";
  if (counts.skipped_images > 0) {
    text += ", " + std::to_string(counts.skipped_images) + " skipped (a missing or corrupt image)";
  }
  if (stopped_early) text += " (stopped early)";
  return text;
}

}  // namespace heslam

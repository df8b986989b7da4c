// The replay's one-line progress (redrawn on a TTY) and its end-of-run summary.
#pragma once

#include <cstddef>
#include <string>

namespace heslam {

struct ReplayCounts {
  std::size_t published = 0;       // frames written, over all --loop passes
  std::size_t total = 0;           // frames per pass
  std::size_t pass_published = 0;  // frames written in the current pass
  std::size_t skipped_images = 0;  // missing or corrupt image files, skipped
  std::size_t unpaired_rows = 0;   // dataset rows without a partner in the other camera
  std::size_t imu_readings = 0;    // IMU readings published (0 without an IMU)
  int pass = 1;                    // 1-based --loop pass
  bool paused = false;
  double elapsed_s = 0.0;  // wall time since the first frame, pauses included
  double paused_s = 0.0;   // of which paused
};

// e.g. "frame 40/95  42%  19.9 fps  ETA 2.8 s" (+ "  imu 401", "  pass 2", "  [paused]").
std::string format_progress_line(const ReplayCounts& counts);

// e.g. "published 95 frames in 4.75 s (20.0 fps); skipped 0 images; 4 unpaired rows" (+ "; 951 IMU
// readings" with an IMU).
std::string format_summary(const ReplayCounts& counts);

// The replay's one-line result for the run's verdict: "160 of 160 frames published", "159 of 160
// frames published, 1 skipped (a missing or corrupt image)", "published 480 frames over 3 passes";
// "(stopped early)" when it did not reach the end.
std::string format_result(const ReplayCounts& counts, bool loop, bool stopped_early);

}  // namespace heslam

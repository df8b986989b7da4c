// Options of heslam-viewer: display or headless, snapshots, recording, ground truth, and what the
// views show. Read from the command line (after the common flags); `usage()` is the --help text,
// including the keys of the windows.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "components/core/image/histogram_equalizer.hpp"
#include "tools/viewer/top_view_renderer.hpp"

namespace heslam::viewer {

struct ViewerOptions {
  // --headless: no window; the views are rendered off-screen and written as PNG snapshots to --out.
  // Also chosen automatically when $DISPLAY is unset.
  bool headless = false;
  // --snapshot-every S: write snapshots every S seconds of wall time (0: only at the end).
  double snapshot_every_s = 0.0;
  // --out DIR: where snapshots and viewer_stats.txt go (empty: nothing is written; headless needs it).
  std::filesystem::path out_dir;
  // --gt FILE: ground truth (TUM, EuRoC csv or KITTI, as heslam-eval reads it) drawn over the map,
  // aligned to the estimate (SE(3) Umeyama on time-associated positions).
  std::filesystem::path gt_file;
  // --gt-extrinsic sensor.yaml: T_BS turning EuRoC body poses into camera poses (heslam-eval's
  // --extrinsic); empty: the ground truth is drawn as given.
  std::filesystem::path gt_extrinsic;
  // --record FILE: the 2D view as a video (VideoWriter, mp4v), or a PNG sequence FILE-stem_NNNNNN.png
  // in FILE's folder when no codec opens the file.
  std::filesystem::path record_file;
  // --rate HZ: how often the drawing thread renders (frames arriving faster are dropped and counted).
  double draw_rate_hz = 20.0;
  // --recent-keyframes N: points whose reference keyframe is one of the N newest are "recent".
  int recent_keyframes = 5;
  // --covisibility-min-weight W: covisibility edges drawn only between keyframes sharing >= W
  // points (ORB-SLAM2's viewer uses 100).
  int covisibility_min_weight = 100;
  // --fit trajectory|map: what the top view (snapshots, the window without viz) is fitted to.
  TopViewFit fit = TopViewFit::kTrajectory;
  // --he-mode MODE: the equalization shown beside the raw image (the frontend's default).
  HeMode he_mode = HistogramEqualizerOptions{}.mode;

  // Throws std::runtime_error with one line naming the flag and what it expects.
  static ViewerOptions parse(const std::vector<std::string>& rest);
  static std::string usage();
};

}  // namespace heslam::viewer

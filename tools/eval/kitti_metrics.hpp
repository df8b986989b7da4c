// The KITTI odometry devkit's drift metrics (and kitti-odom-eval's ATE / RPE) for one sequence.
//
// API:
//   KittiResult k = compute_kitti_metrics(gt, est, KittiOptions{.align = AlignMode::sim3});
//   k.translation_error_percent, k.rotation_error_deg_per_100m, k.ate_m, k.rpe_m, k.rpe_deg
// As kitti-odom-eval (which extends the devkit's evaluate_odometry.cpp):
//   - poses pair by frame index (KITTI files with or without the leading index column);
//   - both trajectories are first expressed relative to the estimate's first frame, then aligned
//     (none: the devkit; se3 / sim3: Umeyama on positions, kitti-odom-eval's 6dof / 7dof);
//   - drift: from every 10th ground-truth frame, sub-sequences of 100, 200, ..., 800 m of
//     ground-truth path; error E = (P_a^-1 P_b)^-1 (Q_a^-1 Q_b); translation |t(E)| / length,
//     rotation acos((trace(R(E)) - 1) / 2) / length, averaged over all sub-sequences;
//   - ATE: rmse of position differences; RPE: mean over consecutive frames of the translation and
//     rotation of (Q_i^-1 Q_i+1)^-1 (P_i^-1 P_i+1).
// Matrices are inverted exactly (not by transposing the rotation), as numpy.linalg.inv does.
#pragma once

#include <cstddef>
#include <vector>

#include "tools/eval/alignment.hpp"
#include "tools/eval/trajectory.hpp"

namespace heslam::eval {

struct KittiOptions {
  // The devkit compares stereo results as they are; monocular results need sim3.
  AlignMode align = AlignMode::none;
  // Sub-sequence lengths of the devkit.
  std::vector<double> lengths_m = {100, 200, 300, 400, 500, 600, 700, 800};
  // The devkit starts a sub-sequence at every 10th frame.
  std::size_t step_frames = 10;
};

struct KittiSegmentError {
  std::int64_t first_frame = 0;
  double length_m = 0.0;
  double translation_error = 0.0;  // metres per metre
  double rotation_error_rad_per_m = 0.0;
};

struct KittiLengthError {
  double length_m = 0.0;
  std::size_t segments = 0;
  double translation_error_percent = 0.0;
  double rotation_error_deg_per_100m = 0.0;
};

struct KittiResult {
  AlignMode align = AlignMode::none;
  Sim3 alignment;
  std::size_t pairs = 0;  // frames present in both
  std::vector<KittiSegmentError> segments;
  std::vector<KittiLengthError> per_length;
  double translation_error_percent = 0.0;  // average over all sub-sequences
  double rotation_error_deg_per_100m = 0.0;
  double ate_m = 0.0;
  double rpe_m = 0.0;
  double rpe_deg = 0.0;
  // The evaluated poses, paired row by row: ground truth relative to the first estimated frame, and
  // the estimate after alignment (for plots).
  Trajectory gt_relative;
  Trajectory est_aligned;
};

// Throws std::runtime_error when the trajectories share no frame index or no sub-sequence fits.
KittiResult compute_kitti_metrics(const Trajectory& gt, const Trajectory& est, const KittiOptions& options = {});

}  // namespace heslam::eval

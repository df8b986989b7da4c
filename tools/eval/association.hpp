// Pairs the poses of a ground truth and an estimate: by time stamp when both have stamps (evo's
// rule), else by frame index.
//
// API:
//   AlignedPair pair = associate(gt, est, AssociationOptions{.max_dt_s = 0.01});
//   pair.gt.poses_wc[k] and pair.est.poses_wc[k] belong together (k < pair.size()).
// Time association (as evo's associate_trajectories): every pose of the shorter trajectory is paired
// with the nearest stamp of the longer one (earliest on ties) when |dt| <= max_dt_s; a pose of the
// longer one may be used twice. Frame-index association pairs poses with equal frame ids (KITTI files
// of the same sequence, with or without the leading index column).
// Interpolation (interpolate_gt): every estimate pose is paired with the ground truth interpolated at
// its stamp (plus est_offset_s) between the two ground-truth poses around it: linear in position,
// slerp in rotation. For a ground truth at another rate than the estimate, or to shift the estimate's
// clock by less than the ground truth's period. Stamps outside the ground truth, or inside a gap of
// more than max_gap_s between two ground-truth poses, are not paired.
// Throws std::runtime_error when nothing overlaps, or when only one side has stamps.
#pragma once

#include <cstddef>
#include <vector>

#include "tools/eval/trajectory.hpp"

namespace heslam::eval {

struct AssociationOptions {
  // Largest |t_gt - t_est| accepted as the same instant; evo's default.
  double max_dt_s = 0.01;
  // Added to the estimate's stamps before matching (clock offset of the estimate).
  double est_offset_s = 0.0;
  // Pair by interpolating the ground truth at the estimate's stamps instead of the nearest stamp.
  bool interpolate_gt = false;
  // With interpolate_gt: the longest gap between two ground-truth poses that is interpolated across.
  double max_gap_s = 0.2;
};

struct AlignedPair {
  Trajectory gt;
  Trajectory est;
  // Rows of the input files the pairs came from (interpolated: the ground-truth pose before the stamp).
  std::vector<std::size_t> gt_rows;
  std::vector<std::size_t> est_rows;
  bool by_time = false;

  std::size_t size() const { return gt.size(); }
};

AlignedPair associate(const Trajectory& gt, const Trajectory& est, const AssociationOptions& options = {});

}  // namespace heslam::eval

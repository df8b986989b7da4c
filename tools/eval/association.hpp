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
};

struct AlignedPair {
  Trajectory gt;
  Trajectory est;
  // Rows of the input files the pairs came from.
  std::vector<std::size_t> gt_rows;
  std::vector<std::size_t> est_rows;
  bool by_time = false;

  std::size_t size() const { return gt.size(); }
};

AlignedPair associate(const Trajectory& gt, const Trajectory& est, const AssociationOptions& options = {});

}  // namespace heslam::eval

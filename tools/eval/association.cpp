// Time and frame-index association of a ground truth and an estimate.
#include "tools/eval/association.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace heslam::eval {

namespace {

// Index of the stamp nearest to `t_s` in ascending `stamps_s`; the earliest one on ties (numpy's
// argmin, as evo uses).
std::size_t nearest(const std::vector<double>& stamps_s, double offset_s, double t_s) {
  const auto it = std::lower_bound(stamps_s.begin(), stamps_s.end(), t_s,
                                   [offset_s](double s, double t) { return s + offset_s < t; });
  std::size_t best = static_cast<std::size_t>(it - stamps_s.begin());
  if (best == stamps_s.size()) best = stamps_s.size() - 1;
  if (best > 0) {
    const double d_before = std::abs(stamps_s[best - 1] + offset_s - t_s);
    const double d_at = std::abs(stamps_s[best] + offset_s - t_s);
    if (d_before <= d_at) best = best - 1;
  }
  // Equal stamps before `best` are earlier indices with the same distance.
  while (best > 0 && stamps_s[best - 1] == stamps_s[best]) --best;
  return best;
}

void associate_by_time(const Trajectory& gt, const Trajectory& est, const AssociationOptions& options,
                       AlignedPair& pair) {
  // evo walks the shorter trajectory and looks each stamp up in the longer one.
  const bool est_longer = est.size() > gt.size();
  const Trajectory& shorter = est_longer ? gt : est;
  const Trajectory& longer = est_longer ? est : gt;
  const double longer_offset_s = est_longer ? options.est_offset_s : 0.0;
  const double shorter_offset_s = est_longer ? 0.0 : options.est_offset_s;
  for (std::size_t i = 0; i < shorter.size(); ++i) {
    const double t_s = shorter.stamps_s[i] + shorter_offset_s;
    const std::size_t j = nearest(longer.stamps_s, longer_offset_s, t_s);
    if (std::abs(longer.stamps_s[j] + longer_offset_s - t_s) > options.max_dt_s) continue;
    pair.gt_rows.push_back(est_longer ? i : j);
    pair.est_rows.push_back(est_longer ? j : i);
  }
}

// Stamps this close are one instant: files store seconds as text, and a double at 1.4e9 s (EuRoC
// stamps) resolves 0.24 microseconds, so the same camera stamp written by two tools can differ by that.
constexpr double kSameInstantS = 1e-6;

// The estimate's stamps are the pairs' stamps; gt holds the interpolated poses (pair.gt is built here).
void associate_by_interpolation(const Trajectory& gt, const Trajectory& est, const AssociationOptions& options,
                                AlignedPair& pair) {
  pair.gt.name = gt.name + " (interpolated)";
  for (std::size_t j = 0; j < est.size(); ++j) {
    const double t_s = est.stamps_s[j] + options.est_offset_s;
    const auto after = std::lower_bound(gt.stamps_s.begin(), gt.stamps_s.end(), t_s - kSameInstantS);
    if (after == gt.stamps_s.end()) continue;
    std::size_t i = static_cast<std::size_t>(after - gt.stamps_s.begin());
    Pose3 T_wc = gt.poses_wc[i];
    if (std::abs(*after - t_s) > kSameInstantS) {
      if (i == 0) continue;
      --i;  // gt stamp i < t_s < gt stamp i + 1
      const double span_s = gt.stamps_s[i + 1] - gt.stamps_s[i];
      if (span_s > options.max_gap_s) continue;
      const double a = (t_s - gt.stamps_s[i]) / span_s;
      const Eigen::Quaterniond q0(gt.poses_wc[i].rotation());
      const Eigen::Quaterniond q1(gt.poses_wc[i + 1].rotation());
      T_wc = Pose3::Identity();
      T_wc.linear() = q0.slerp(a, q1).toRotationMatrix();
      T_wc.translation() = (1.0 - a) * gt.poses_wc[i].translation() + a * gt.poses_wc[i + 1].translation();
    }
    pair.gt.push_back(T_wc, static_cast<std::int64_t>(pair.gt.size()), t_s);
    pair.gt_rows.push_back(i);
    pair.est_rows.push_back(j);
  }
}

void associate_by_frame_id(const Trajectory& gt, const Trajectory& est, AlignedPair& pair) {
  std::map<std::int64_t, std::size_t> gt_row_of_id;
  for (std::size_t i = 0; i < gt.size(); ++i) gt_row_of_id.emplace(gt.frame_ids[i], i);
  for (std::size_t j = 0; j < est.size(); ++j) {
    const auto it = gt_row_of_id.find(est.frame_ids[j]);
    if (it == gt_row_of_id.end()) continue;
    pair.gt_rows.push_back(it->second);
    pair.est_rows.push_back(j);
  }
}

}  // namespace

AlignedPair associate(const Trajectory& gt, const Trajectory& est, const AssociationOptions& options) {
  if (gt.empty() || est.empty()) throw std::runtime_error("cannot associate an empty trajectory");
  if (gt.has_stamps() != est.has_stamps()) {
    const Trajectory& without = gt.has_stamps() ? est : gt;
    throw std::runtime_error("cannot associate: " + without.name +
                             " has no time stamps but the other trajectory does (give the KITTI "
                             "file its times.txt with --gt-times / --est-times)");
  }
  AlignedPair pair;
  pair.by_time = gt.has_stamps();
  if (pair.by_time && options.interpolate_gt) {
    associate_by_interpolation(gt, est, options, pair);
  } else if (pair.by_time) {
    associate_by_time(gt, est, options, pair);
  } else {
    associate_by_frame_id(gt, est, pair);
  }
  if (pair.gt_rows.empty()) {
    throw std::runtime_error(
        "no overlap between " + gt.name + " and " + est.name +
        (pair.by_time ? (options.interpolate_gt ? " (no estimate stamp inside the ground truth's time span)"
                                                : " (no stamps within " + std::to_string(options.max_dt_s) + " s)")
                      : " (no common frame index)"));
  }
  if (!(pair.by_time && options.interpolate_gt)) pair.gt = gt.subset(pair.gt_rows);
  pair.est = est.subset(pair.est_rows);
  return pair;
}

}  // namespace heslam::eval

// KITTI odometry drift metrics, ATE and RPE following kitti-odom-eval / the KITTI devkit.
#include "tools/eval/kitti_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>

#include <Eigen/LU>

namespace heslam::eval {

namespace {

using Matrix4 = Eigen::Matrix4d;

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr double kPercent = 100.0;
constexpr double kPer100m = 100.0;

// The devkit's rotation error: acos of the trace, clamped.
double rotation_error_rad(const Matrix4& E) {
  const double d = 0.5 * (E(0, 0) + E(1, 1) + E(2, 2) - 1.0);
  return std::acos(std::clamp(d, -1.0, 1.0));
}

double translation_error_m(const Matrix4& E) { return E.block<3, 1>(0, 3).norm(); }

// Index of the first ground-truth row whose path distance exceeds dist[first] + length, or -1.
std::ptrdiff_t last_frame_from_length(const std::vector<double>& dist_m, std::size_t first, double length_m) {
  for (std::size_t i = first; i < dist_m.size(); ++i) {
    if (dist_m[i] > dist_m[first] + length_m) return static_cast<std::ptrdiff_t>(i);
  }
  return -1;
}

}  // namespace

KittiResult compute_kitti_metrics(const Trajectory& gt, const Trajectory& est, const KittiOptions& options) {
  KittiResult result;
  result.align = options.align;

  // Poses by frame index; the estimate keeps only frames the ground truth has.
  std::map<std::int64_t, Matrix4> gt_by_id;
  for (std::size_t i = 0; i < gt.size(); ++i) gt_by_id.emplace(gt.frame_ids[i], gt.poses_wc[i].matrix());
  std::map<std::int64_t, Matrix4> est_by_id;
  for (std::size_t i = 0; i < est.size(); ++i) {
    if (gt_by_id.count(est.frame_ids[i]) != 0) est_by_id.emplace(est.frame_ids[i], est.poses_wc[i].matrix());
  }
  if (est_by_id.empty()) {
    throw std::runtime_error("no common frame index between " + gt.name + " and " + est.name);
  }
  result.pairs = est_by_id.size();

  // Both relative to the estimate's first frame (the ground truth's distances below use its own
  // unmodified poses: path length does not change under a rigid transform).
  const std::int64_t first_id = est_by_id.begin()->first;
  const Matrix4 est_0_inv = est_by_id.at(first_id).inverse();
  const Matrix4 gt_0_inv = gt_by_id.at(first_id).inverse();
  std::map<std::int64_t, Matrix4> gt_rel;
  for (auto& [id, P] : est_by_id) {
    P = est_0_inv * P;
    gt_rel.emplace(id, gt_0_inv * gt_by_id.at(id));
  }

  if (options.align == AlignMode::se3 || options.align == AlignMode::sim3) {
    std::vector<Eigen::Vector3d> from;
    std::vector<Eigen::Vector3d> to;
    for (const auto& [id, P] : est_by_id) {
      from.push_back(P.block<3, 1>(0, 3));
      to.push_back(gt_rel.at(id).block<3, 1>(0, 3));
    }
    result.alignment = umeyama(from, to, options.align == AlignMode::sim3);
    Matrix4 A = Matrix4::Identity();
    A.block<3, 3>(0, 0) = result.alignment.R;
    A.block<3, 1>(0, 3) = result.alignment.t;
    for (auto& [id, P] : est_by_id) {
      P.block<3, 1>(0, 3) *= result.alignment.scale;
      P = (A * P).eval();
    }
  }

  // Drift over sub-sequences of ground-truth path length.
  std::vector<double> dist_m(gt.size(), 0.0);
  for (std::size_t i = 1; i < gt.size(); ++i) {
    dist_m[i] = dist_m[i - 1] + (gt.position_m(i) - gt.position_m(i - 1)).norm();
  }
  for (std::size_t first = 0; first < gt.size(); first += options.step_frames) {
    for (const double length_m : options.lengths_m) {
      const std::ptrdiff_t last = last_frame_from_length(dist_m, first, length_m);
      if (last < 0) continue;
      const std::int64_t id_a = gt.frame_ids[first];
      const std::int64_t id_b = gt.frame_ids[static_cast<std::size_t>(last)];
      const auto est_a = est_by_id.find(id_a);
      const auto est_b = est_by_id.find(id_b);
      if (est_a == est_by_id.end() || est_b == est_by_id.end()) continue;
      const Matrix4 gt_delta = gt_rel.at(id_a).inverse() * gt_rel.at(id_b);
      const Matrix4 est_delta = est_a->second.inverse() * est_b->second;
      const Matrix4 E = est_delta.inverse() * gt_delta;
      result.segments.push_back({id_a, length_m, translation_error_m(E) / length_m, rotation_error_rad(E) / length_m});
    }
  }
  if (result.segments.empty()) {
    throw std::runtime_error("KITTI metrics: no sub-sequence of " + std::to_string(options.lengths_m.front()) +
                             " m or more is covered by both " + gt.name + " and " + est.name);
  }
  double t_sum = 0.0;
  double r_sum = 0.0;
  for (const KittiSegmentError& s : result.segments) {
    t_sum += s.translation_error;
    r_sum += s.rotation_error_rad_per_m;
  }
  const double n_segments = static_cast<double>(result.segments.size());
  result.translation_error_percent = t_sum / n_segments * kPercent;
  result.rotation_error_deg_per_100m = r_sum / n_segments * kRadToDeg * kPer100m;
  for (const double length_m : options.lengths_m) {
    KittiLengthError per_length;
    per_length.length_m = length_m;
    double t = 0.0;
    double r = 0.0;
    for (const KittiSegmentError& s : result.segments) {
      if (s.length_m != length_m) continue;
      ++per_length.segments;
      t += s.translation_error;
      r += s.rotation_error_rad_per_m;
    }
    if (per_length.segments > 0) {
      per_length.translation_error_percent = t / static_cast<double>(per_length.segments) * kPercent;
      per_length.rotation_error_deg_per_100m = r / static_cast<double>(per_length.segments) * kRadToDeg * kPer100m;
    }
    result.per_length.push_back(per_length);
  }

  // ATE over every estimated frame; RPE over consecutive frame indices.
  double squared_sum = 0.0;
  result.gt_relative.name = gt.name;
  result.est_aligned.name = est.name;
  for (const auto& [id, P] : est_by_id) {
    squared_sum += (gt_rel.at(id).block<3, 1>(0, 3) - P.block<3, 1>(0, 3)).squaredNorm();
    result.gt_relative.push_back(Pose3(gt_rel.at(id)), id);
    result.est_aligned.push_back(Pose3(P), id);
  }
  result.ate_m = std::sqrt(squared_sum / static_cast<double>(est_by_id.size()));
  double rpe_t_sum = 0.0;
  double rpe_r_sum = 0.0;
  std::size_t rpe_count = 0;
  for (auto it = est_by_id.begin(); it != est_by_id.end(); ++it) {
    const auto next = est_by_id.find(it->first + 1);
    if (next == est_by_id.end()) continue;
    const Matrix4 gt_motion = gt_rel.at(it->first).inverse() * gt_rel.at(next->first);
    const Matrix4 est_motion = it->second.inverse() * next->second;
    const Matrix4 E = gt_motion.inverse() * est_motion;
    rpe_t_sum += translation_error_m(E);
    rpe_r_sum += rotation_error_rad(E);
    ++rpe_count;
  }
  if (rpe_count > 0) {
    result.rpe_m = rpe_t_sum / static_cast<double>(rpe_count);
    result.rpe_deg = rpe_r_sum / static_cast<double>(rpe_count) * kRadToDeg;
  }
  return result;
}

}  // namespace heslam::eval

// Relative pose error with evo's pair selection.
#include "tools/eval/rpe.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace heslam::eval {

namespace {

std::vector<std::pair<std::size_t, std::size_t>> pairs_by_frames(std::size_t n, std::size_t delta, bool all_pairs) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  if (all_pairs) {
    for (std::size_t i = 0; i + delta < n; ++i) pairs.emplace_back(i, i + delta);
  } else {
    for (std::size_t i = 0; i + delta < n; i += delta) pairs.emplace_back(i, i + delta);
  }
  return pairs;
}

std::vector<std::pair<std::size_t, std::size_t>> pairs_by_path(const Trajectory& est, double delta_m, bool all_pairs,
                                                               double tol_m) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  const std::size_t n = est.size();
  if (all_pairs) {
    std::vector<double> distance_m(n, 0.0);
    for (std::size_t i = 1; i < n; ++i) {
      distance_m[i] = distance_m[i - 1] + (est.position_m(i) - est.position_m(i - 1)).norm();
    }
    for (std::size_t i = 0; i + 1 < n; ++i) {
      std::size_t best = i + 1;
      double best_gap = std::abs(distance_m[best] - distance_m[i] - delta_m);
      for (std::size_t j = i + 2; j < n; ++j) {
        const double gap = std::abs(distance_m[j] - distance_m[i] - delta_m);
        if (gap < best_gap) {
          best_gap = gap;
          best = j;
        }
      }
      if (best_gap <= tol_m) pairs.emplace_back(i, best);
    }
    return pairs;
  }
  std::vector<std::size_t> rows;
  double path_m = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) path_m += (est.position_m(i) - est.position_m(i - 1)).norm();
    if (path_m >= delta_m) {
      rows.push_back(i);
      path_m = 0.0;
    }
  }
  for (std::size_t k = 1; k < rows.size(); ++k) pairs.emplace_back(rows[k - 1], rows[k]);
  return pairs;
}

}  // namespace

std::optional<DeltaUnit> parse_delta_unit(std::string_view name) {
  if (name == "frames" || name == "f") return DeltaUnit::frames;
  if (name == "m" || name == "meters" || name == "metres") return DeltaUnit::meters;
  return std::nullopt;
}

const char* delta_unit_name(DeltaUnit unit) { return unit == DeltaUnit::frames ? "frames" : "m"; }

std::vector<std::pair<std::size_t, std::size_t>> rpe_pairs(const Trajectory& est, const RpeOptions& options) {
  if (!(options.delta > 0.0)) throw std::runtime_error("RPE: delta must be positive");
  if (options.unit == DeltaUnit::frames) {
    if (options.delta != std::floor(options.delta)) {
      throw std::runtime_error("RPE: a delta in frames must be a whole number, got " + std::to_string(options.delta));
    }
    return pairs_by_frames(est.size(), static_cast<std::size_t>(options.delta), options.all_pairs);
  }
  return pairs_by_path(est, options.delta, options.all_pairs, options.rel_tol * options.delta);
}

RpeResult compute_rpe(const AlignedPair& pair, const RpeOptions& options) {
  RpeResult result;
  result.options = options;
  Trajectory est = pair.est;
  apply_sim3(est, compute_alignment(pair.gt, pair.est, options.align));
  result.pairs = rpe_pairs(est, options);
  if (result.pairs.empty()) {
    throw std::runtime_error("RPE: no pose pair " + std::to_string(options.delta) + " " +
                             delta_unit_name(options.unit) + " apart in " + est.name + " (" +
                             std::to_string(est.size()) + " poses, " + std::to_string(est.path_length_m()) + " m)");
  }
  for (const auto& [i, j] : result.pairs) {
    const Pose3 gt_motion = pair.gt.poses_wc[i].inverse() * pair.gt.poses_wc[j];
    const Pose3 est_motion = est.poses_wc[i].inverse() * est.poses_wc[j];
    const Pose3 E = gt_motion.inverse() * est_motion;
    result.translation_errors_m.push_back(E.translation().norm());
    result.rotation_errors_deg.push_back(rotation_angle_rad(E.linear()) * 180.0 / std::numbers::pi);
  }
  result.translation_m = compute_stats(result.translation_errors_m);
  result.rotation_deg = compute_stats(result.rotation_errors_deg);
  return result;
}

}  // namespace heslam::eval

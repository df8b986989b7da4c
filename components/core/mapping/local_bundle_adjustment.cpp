// Local bundle adjustment of the new keyframe's neighbourhood (its own sparse Levenberg-Marquardt solver).
#include "components/core/mapping/local_bundle_adjustment.hpp"

#include <cmath>

#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"

namespace heslam {

LocalBundleAdjustmentWindow::LocalBundleAdjustmentWindow(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                         const LocalBundleAdjustmentOptions& options,
                                                         const std::vector<KeyframeId>& more_free,
                                                         const std::set<KeyframeId>& more_fixed)
    : map_(map), camera_(camera), options_(options) {
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled || map.keyframes.empty()) return;
  valid_ = true;
  const KeyframeId origin_id = map_origin(map, kf->map_id);  // each map of the atlas has its own

  free_kfs_.insert(kf_id);
  for (const auto& [neighbour, weight] : kf->covisible) {
    const Keyframe* other = map.keyframe(neighbour);
    if (other != nullptr && !other->culled) free_kfs_.insert(neighbour);
  }
  free_kfs_.insert(more_free.begin(), more_free.end());
  for (const KeyframeId id : more_fixed) free_kfs_.erase(id);
  std::set<PointId> point_ids;
  for (const KeyframeId id : free_kfs_) {
    for (const PointId point_id : map.keyframe(id)->point_ids) {
      if (point_id != kNoId && map.point(point_id) != nullptr) point_ids.insert(point_id);
    }
  }
  fixed_kfs_ = more_fixed;
  for (const PointId point_id : point_ids) {
    for (const auto& [observer, index] : map.point(point_id)->observations) {
      if (free_kfs_.count(observer) == 0) fixed_kfs_.insert(observer);
    }
  }
  if (free_kfs_.count(origin_id) != 0) {
    free_kfs_.erase(origin_id);
    fixed_kfs_.insert(origin_id);
  }
  if (fixed_kfs_.empty() && !free_kfs_.empty()) {  // nothing anchors the gauge: hold the oldest
    fixed_kfs_.insert(*free_kfs_.begin());
    free_kfs_.erase(free_kfs_.begin());
  }

  // Parameters in id order (the solver is sequential: lockstep runs are reproducible).
  problem_.camera = camera;
  for (const auto& [id, kf_unused] : map.keyframes) {
    if (free_kfs_.count(id) == 0 && fixed_kfs_.count(id) == 0) continue;
    pose_index_[id] = problem_.poses.size();
    problem_.poses.push_back(to_pose_block(map.keyframe(id)->T_wc));
  }
  for (const PointId id : point_ids) {
    point_index_[id] = problem_.points.size();
    problem_.points.push_back(map.point(id)->p_w);
  }

  for (const PointId point_id : point_ids) {
    const std::size_t point = point_index_.at(point_id);
    for (const auto& [observer, index] : map.point(point_id)->observations) {
      const Keyframe* observer_kf = map.keyframe(observer);
      const auto pose = pose_index_.find(observer);
      if (observer_kf == nullptr || pose == pose_index_.end()) continue;
      const std::size_t i = static_cast<std::size_t>(index);
      const StereoFeatures& features = observer_kf->features;
      const Keypoint& kp = features.keypoints[i];
      const bool stereo = features.has_stereo(i);
      Observation obs{observer, index, point_id, stereo, stereo ? options.stereo_chi2 : options.mono_chi2};
      obs.pose = pose->second;
      obs.point = point;
      obs.u_px = kp.u_px;
      obs.v_px = kp.v_px;
      obs.disparity_px = stereo ? kp.u_px - features.u_right_px[i] : 0.0;
      obs.inv_sigma2 = features.pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)];
      observations_.push_back(obs);
    }
  }

  result_.free_keyframes = static_cast<int>(free_kfs_.size());
  result_.fixed_keyframes = static_cast<int>(fixed_kfs_.size());
  result_.points = static_cast<int>(problem_.points.size());
  result_.observations = static_cast<int>(observations_.size());
  result_.initial_rms_px = rms();
  if (!solvable()) return;

  for (Observation& obs : observations_) {  // a point behind an observer cannot enter the problem
    double chi2 = 0.0;
    obs.inlier = chi2_of(obs, chi2);
  }
  problem_.pose_fixed.assign(problem_.poses.size(), false);
  for (const KeyframeId id : fixed_kfs_) problem_.pose_fixed[pose_index_.at(id)] = true;
  problem_.observations.reserve(observations_.size());
  for (const Observation& obs : observations_) {  // grouped by point, as the solver wants
    // The square root of the level's float inv_sigma2, in float (as the keypoint model always had it).
    const double inv_sigma = std::sqrt(static_cast<float>(obs.inv_sigma2));
    BundleAdjustmentObservation term;
    term.pose = static_cast<int>(obs.pose);
    term.point = static_cast<int>(obs.point);
    term.u_px = obs.u_px;
    term.v_px = obs.v_px;
    term.disparity_px = obs.disparity_px;
    term.weight = inv_sigma;
    term.disparity_weight = inv_sigma / options.disparity_sigma_ratio;
    term.huber_delta = std::sqrt(obs.chi2_threshold);  // Huber at the chi2 95 % threshold
    term.stereo = obs.stereo;
    term.active = obs.inlier;
    problem_.observations.push_back(term);
  }
}

// Whitened squared error and positive depth of one observation at the current parameters.
bool LocalBundleAdjustmentWindow::chi2_of(const Observation& obs, double& chi2) const {
  const Eigen::Vector3d pc = transform_to_camera(problem_.poses[obs.pose], problem_.points[obs.point]);
  if (pc.z() <= 0.0) return false;
  const Eigen::Vector2d uv = camera_.project(pc);
  double error2 = (uv - Eigen::Vector2d(obs.u_px, obs.v_px)).squaredNorm();
  if (obs.stereo) {
    const double dd = (camera_.bf() / pc.z() - obs.disparity_px) / options_.disparity_sigma_ratio;
    error2 += dd * dd;
  }
  chi2 = error2 * obs.inv_sigma2;
  return true;
}

double LocalBundleAdjustmentWindow::rms() const {
  double sum = 0.0;
  int count = 0;
  for (const Observation& obs : observations_) {
    double chi2 = 0.0;
    if (!obs.inlier || !chi2_of(obs, chi2)) continue;
    sum += chi2;
    ++count;
  }
  return count > 0 ? std::sqrt(sum / count) : 0.0;
}

bool LocalBundleAdjustmentWindow::solve(BundleAdjustmentExtraTerms* extra) {
  problem_.extra = extra;
  BundleAdjustmentSolverOptions solver_options;
  solver_options.stop_requested = options_.stop_requested;
  solver_options.max_iterations = options_.first_pass_iterations;
  BundleAdjustmentSolverSummary summary = solve_bundle_adjustment(problem_, solver_options);
  initial_cost_ = summary.initial_cost;
  bool stopped = summary.stopped;
  // As ORB-SLAM2: a stop requested during the first pass also skips the second.
  if (!stopped) {
    // Second pass on the inliers of the first. ORB-SLAM2 also drops the robust kernel here; the
    // Huber kernel is kept instead: every remaining residual starts inside the kernel's quadratic
    // region, where the two are identical.
    for (std::size_t k = 0; k < observations_.size(); ++k) {
      double chi2 = 0.0;
      observations_[k].inlier = chi2_of(observations_[k], chi2) && chi2 <= observations_[k].chi2_threshold;
      problem_.observations[k].active = observations_[k].inlier;
    }
    solver_options.max_iterations = options_.second_pass_iterations;
    summary = solve_bundle_adjustment(problem_, solver_options);
    stopped = summary.stopped;
  }
  final_cost_ = summary.final_cost;
  problem_.extra = nullptr;
  result_.aborted = stopped;
  return stopped;
}

bool LocalBundleAdjustmentWindow::finite() const {
  for (const KeyframeId id : free_kfs_) {
    for (const double x : problem_.poses[pose_index_.at(id)]) {
      if (!std::isfinite(x)) return false;
    }
  }
  for (const Eigen::Vector3d& point : problem_.points) {
    if (!point.allFinite()) return false;
  }
  return true;
}

void LocalBundleAdjustmentWindow::write_back(MapChanges& changes) {
  // Write back, then unlink the observations that are still outliers.
  for (const KeyframeId id : free_kfs_) {
    map_.keyframe(id)->T_wc = from_pose_block(problem_.poses[pose_index_.at(id)]);
    changes.changed_keyframes.insert(id);
  }
  for (const auto& [id, index] : point_index_) map_.point(id)->p_w = problem_.points[index];
  for (Observation& obs : observations_) {
    double chi2 = 0.0;
    obs.inlier = chi2_of(obs, chi2) && chi2 <= obs.chi2_threshold;
  }
  result_.final_rms_px = rms();
  for (const Observation& obs : observations_) {
    if (obs.inlier || map_.point(obs.point_id) == nullptr) continue;
    erase_observation(map_, obs.point_id, obs.kf_id);
    ++result_.outliers_removed;
    changes.changed_keyframes.insert(obs.kf_id);
    const MapPoint* point = map_.point(obs.point_id);
    if (observation_weight(map_, *point) <= 2) {  // ORB-SLAM2: too weakly observed to keep
      erase_point(map_, obs.point_id);
      changes.removed_points[obs.point_id] = kNoId;
    }
  }
  for (const auto& [id, index] : point_index_) {
    if (map_.point(id) == nullptr) {
      changes.changed_points.erase(id);
      continue;
    }
    update_point_statistics(map_, id);
    changes.changed_points.insert(id);
  }
}

LocalBundleAdjustmentResult local_bundle_adjustment(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                    const LocalBundleAdjustmentOptions& options, MapChanges& changes) {
  LocalBundleAdjustmentWindow window(map, kf_id, camera, options);
  if (!window.solvable()) return window.result();
  window.solve(nullptr);
  window.write_back(changes);
  return window.result();
}

}  // namespace heslam

// Local bundle adjustment of the new keyframe's neighbourhood (its own sparse Levenberg-Marquardt solver).
#include "components/core/mapping/local_bundle_adjustment.hpp"

#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include "components/core/mapping/bundle_adjustment_solver.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"

namespace heslam {
namespace {

// One observation with what its chi2 needs, looked up once: the chi2 is evaluated three or four
// times per observation, and map / index lookups there were a third of the local BA's own time.
struct Observation {
  KeyframeId kf_id;
  int index;
  PointId point_id;
  bool stereo;
  double chi2_threshold;
  std::size_t pose = 0;   // index into the problem's poses
  std::size_t point = 0;  // ... and points
  double u_px = 0.0;
  double v_px = 0.0;
  double disparity_px = 0.0;  // u - u_right (computed in float, as the keypoints are)
  double inv_sigma2 = 0.0;    // of the keypoint's pyramid level
  bool inlier = true;
};

}  // namespace

LocalBundleAdjustmentResult local_bundle_adjustment(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                    const LocalBundleAdjustmentOptions& options, MapChanges& changes) {
  LocalBundleAdjustmentResult result;
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled || map.keyframes.empty()) return result;
  const KeyframeId origin_id = map_origin(map, kf->map_id);  // each map of the atlas has its own

  std::set<KeyframeId> free_kfs{kf_id};
  for (const auto& [neighbour, weight] : kf->covisible) {
    const Keyframe* other = map.keyframe(neighbour);
    if (other != nullptr && !other->culled) free_kfs.insert(neighbour);
  }
  std::set<PointId> point_ids;
  for (const KeyframeId id : free_kfs) {
    for (const PointId point_id : map.keyframe(id)->point_ids) {
      if (point_id != kNoId && map.point(point_id) != nullptr) point_ids.insert(point_id);
    }
  }
  std::set<KeyframeId> fixed_kfs;
  for (const PointId point_id : point_ids) {
    for (const auto& [observer, index] : map.point(point_id)->observations) {
      if (free_kfs.count(observer) == 0) fixed_kfs.insert(observer);
    }
  }
  if (free_kfs.count(origin_id) != 0) {
    free_kfs.erase(origin_id);
    fixed_kfs.insert(origin_id);
  }
  if (fixed_kfs.empty() && !free_kfs.empty()) {  // nothing anchors the gauge: hold the oldest
    fixed_kfs.insert(*free_kfs.begin());
    free_kfs.erase(free_kfs.begin());
  }

  // Parameters in id order (the solver is sequential: lockstep runs are reproducible).
  BundleAdjustmentProblem problem;
  problem.camera = camera;
  std::map<KeyframeId, std::size_t> pose_index;
  for (const auto& [id, kf_unused] : map.keyframes) {
    if (free_kfs.count(id) == 0 && fixed_kfs.count(id) == 0) continue;
    pose_index[id] = problem.poses.size();
    problem.poses.push_back(to_pose_block(map.keyframe(id)->T_wc));
  }
  std::map<PointId, std::size_t> point_index;
  for (const PointId id : point_ids) {
    point_index[id] = problem.points.size();
    problem.points.push_back(map.point(id)->p_w);
  }
  const auto pose_of = [&](KeyframeId id) -> PoseBlock& { return problem.poses[pose_index.at(id)]; };

  std::vector<Observation> observations;
  for (const PointId point_id : point_ids) {
    const std::size_t point = point_index.at(point_id);
    for (const auto& [observer, index] : map.point(point_id)->observations) {
      const Keyframe* observer_kf = map.keyframe(observer);
      const auto pose = pose_index.find(observer);
      if (observer_kf == nullptr || pose == pose_index.end()) continue;
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
      observations.push_back(obs);
    }
  }

  // Whitened squared error and positive depth of one observation at the current parameters.
  const auto chi2_of = [&](const Observation& obs, double& chi2) {
    const Eigen::Vector3d pc = transform_to_camera(problem.poses[obs.pose], problem.points[obs.point]);
    if (pc.z() <= 0.0) return false;
    const Eigen::Vector2d uv = camera.project(pc);
    double error2 = (uv - Eigen::Vector2d(obs.u_px, obs.v_px)).squaredNorm();
    if (obs.stereo) {
      const double dd = (camera.bf() / pc.z() - obs.disparity_px) / options.disparity_sigma_ratio;
      error2 += dd * dd;
    }
    chi2 = error2 * obs.inv_sigma2;
    return true;
  };
  const auto rms = [&]() {
    double sum = 0.0;
    int count = 0;
    for (const Observation& obs : observations) {
      double chi2 = 0.0;
      if (!obs.inlier || !chi2_of(obs, chi2)) continue;
      sum += chi2;
      ++count;
    }
    return count > 0 ? std::sqrt(sum / count) : 0.0;
  };

  result.free_keyframes = static_cast<int>(free_kfs.size());
  result.fixed_keyframes = static_cast<int>(fixed_kfs.size());
  result.points = static_cast<int>(problem.points.size());
  result.observations = static_cast<int>(observations.size());
  result.initial_rms_px = rms();
  if (free_kfs.empty() || observations.empty()) return result;

  for (Observation& obs : observations) {  // a point behind an observer cannot enter the problem
    double chi2 = 0.0;
    obs.inlier = chi2_of(obs, chi2);
  }
  problem.pose_fixed.assign(problem.poses.size(), false);
  for (const KeyframeId id : fixed_kfs) problem.pose_fixed[pose_index.at(id)] = true;
  problem.observations.reserve(observations.size());
  for (const Observation& obs : observations) {  // grouped by point, as the solver wants
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
    problem.observations.push_back(term);
  }

  BundleAdjustmentSolverOptions solver_options;
  solver_options.stop_requested = options.stop_requested;
  solver_options.max_iterations = options.first_pass_iterations;
  bool stopped = solve_bundle_adjustment(problem, solver_options).stopped;
  // As ORB-SLAM2: a stop requested during the first pass also skips the second.
  if (!stopped) {
    // Second pass on the inliers of the first. ORB-SLAM2 also drops the robust kernel here; the
    // Huber kernel is kept instead: every remaining residual starts inside the kernel's quadratic
    // region, where the two are identical.
    for (std::size_t k = 0; k < observations.size(); ++k) {
      double chi2 = 0.0;
      observations[k].inlier = chi2_of(observations[k], chi2) && chi2 <= observations[k].chi2_threshold;
      problem.observations[k].active = observations[k].inlier;
    }
    solver_options.max_iterations = options.second_pass_iterations;
    stopped = solve_bundle_adjustment(problem, solver_options).stopped;
  }
  result.aborted = stopped;

  // Write back, then unlink the observations that are still outliers.
  for (const KeyframeId id : free_kfs) {
    map.keyframe(id)->T_wc = from_pose_block(pose_of(id));
    changes.changed_keyframes.insert(id);
  }
  for (const auto& [id, index] : point_index) map.point(id)->p_w = problem.points[index];
  for (Observation& obs : observations) {
    double chi2 = 0.0;
    obs.inlier = chi2_of(obs, chi2) && chi2 <= obs.chi2_threshold;
  }
  result.final_rms_px = rms();
  for (const Observation& obs : observations) {
    if (obs.inlier || map.point(obs.point_id) == nullptr) continue;
    erase_observation(map, obs.point_id, obs.kf_id);
    ++result.outliers_removed;
    changes.changed_keyframes.insert(obs.kf_id);
    const MapPoint* point = map.point(obs.point_id);
    if (observation_weight(map, *point) <= 2) {  // ORB-SLAM2: too weakly observed to keep
      erase_point(map, obs.point_id);
      changes.removed_points[obs.point_id] = kNoId;
    }
  }
  for (const auto& [id, index] : point_index) {
    if (map.point(id) == nullptr) {
      changes.changed_points.erase(id);
      continue;
    }
    update_point_statistics(map, id);
    changes.changed_points.insert(id);
  }
  return result;
}

}  // namespace heslam

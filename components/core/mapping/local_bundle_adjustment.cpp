// Local bundle adjustment of the new keyframe's neighbourhood with Ceres.
#include "components/core/mapping/local_bundle_adjustment.hpp"

#include <array>
#include <deque>
#include <functional>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include <ceres/ceres.h>

#include "components/core/mapping/bundle_adjustment_terms.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"

namespace heslam {
namespace {

struct Observation {
  KeyframeId kf_id;
  int index;
  PointId point_id;
  bool stereo;
  double chi2_threshold;
  ceres::ResidualBlockId block = nullptr;
  bool inlier = true;
};

// Stops the solver after an iteration once a stop is requested; the parameters reached so far are kept.
class StopCallback : public ceres::IterationCallback {
 public:
  explicit StopCallback(const std::function<bool()>& stop_requested) : stop_requested_(stop_requested) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (stop_requested_ && stop_requested_()) stopped_ = true;
    return stopped_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }
  bool stopped() const { return stopped_; }

 private:
  const std::function<bool()>& stop_requested_;
  bool stopped_ = false;
};

}  // namespace

LocalBundleAdjustmentResult local_bundle_adjustment(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                    const LocalBundleAdjustmentOptions& options,
                                                    MapChanges& changes) {
  LocalBundleAdjustmentResult result;
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled || map.keyframes.empty()) return result;
  const KeyframeId origin_id = map.keyframes.begin()->first;

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

  // Parameters live in two vectors filled in id order: Ceres orders blocks of an elimination group
  // by address, so contiguous storage makes the solve (and lockstep runs) reproducible.
  std::vector<PoseBlock> pose_storage;
  std::map<KeyframeId, std::size_t> pose_index;
  for (const auto& [id, kf_unused] : map.keyframes) {
    if (free_kfs.count(id) == 0 && fixed_kfs.count(id) == 0) continue;
    pose_index[id] = pose_storage.size();
    pose_storage.push_back(to_pose_block(map.keyframe(id)->T_wc));
  }
  std::vector<Eigen::Vector3d> point_storage;
  std::map<PointId, std::size_t> point_index;
  for (const PointId id : point_ids) {
    point_index[id] = point_storage.size();
    point_storage.push_back(map.point(id)->p_w);
  }
  const auto pose_of = [&](KeyframeId id) -> PoseBlock& { return pose_storage[pose_index.at(id)]; };
  const auto point_of = [&](PointId id) -> Eigen::Vector3d& { return point_storage[point_index.at(id)]; };

  std::vector<Observation> observations;
  for (const PointId point_id : point_ids) {
    for (const auto& [observer, index] : map.point(point_id)->observations) {
      const Keyframe* observer_kf = map.keyframe(observer);
      if (observer_kf == nullptr || pose_index.count(observer) == 0) continue;
      const bool stereo = observer_kf->features.has_stereo(static_cast<std::size_t>(index));
      observations.push_back({observer, index, point_id, stereo, stereo ? options.stereo_chi2 : options.mono_chi2});
    }
  }

  PoseManifold pose_manifold;
  // One loss per threshold and the costs in one array, owned here: a problem of thousands of
  // residuals otherwise makes two heap allocations per residual and frees them again (measured:
  // allocation was about a tenth of a local BA's time; docs/benchmarks.md, issue 17).
  ceres::HuberLoss mono_loss(std::sqrt(options.mono_chi2));
  ceres::HuberLoss stereo_loss(std::sqrt(options.stereo_chi2));
  std::deque<ReprojectionCost> costs;  // a deque: elements never move, Ceres keeps their addresses
  const auto build_problem = [&](ceres::Problem& problem) {
    for (Observation& obs : observations) {
      obs.block = nullptr;
      if (!obs.inlier) continue;
      const Keyframe& observer = *map.keyframe(obs.kf_id);
      const std::size_t i = static_cast<std::size_t>(obs.index);
      const Keypoint& kp = observer.features.keypoints[i];
      const double inv_sigma = std::sqrt(observer.features.pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)]);
      costs.emplace_back(camera, kp.u_px, kp.v_px, obs.stereo ? observer.features.u_right_px[i] : 0.0, inv_sigma,
                         obs.stereo, options.disparity_sigma_ratio);
      obs.block = problem.AddResidualBlock(&costs.back(), obs.stereo ? &stereo_loss : &mono_loss,
                                           pose_of(obs.kf_id).data(), point_of(obs.point_id).data());
    }
    for (PoseBlock& pose : pose_storage) {
      if (problem.HasParameterBlock(pose.data())) problem.SetManifold(pose.data(), &pose_manifold);
    }
    for (const KeyframeId id : fixed_kfs) {
      if (problem.HasParameterBlock(pose_of(id).data())) problem.SetParameterBlockConstant(pose_of(id).data());
    }
  };

  // Whitened squared error and positive depth of one observation at the current parameters.
  const auto chi2_of = [&](const Observation& obs, double& chi2) {
    const Keyframe& observer = *map.keyframe(obs.kf_id);
    const std::size_t i = static_cast<std::size_t>(obs.index);
    const Keypoint& kp = observer.features.keypoints[i];
    const Eigen::Vector3d pc = transform_to_camera(pose_of(obs.kf_id), point_of(obs.point_id));
    if (pc.z() <= 0.0) return false;
    const Eigen::Vector2d uv = camera.project(pc);
    double error2 = (uv - Eigen::Vector2d(kp.u_px, kp.v_px)).squaredNorm();
    if (obs.stereo) {
      const double disparity = kp.u_px - observer.features.u_right_px[i];
      const double dd = (camera.bf() / pc.z() - disparity) / options.disparity_sigma_ratio;
      error2 += dd * dd;
    }
    chi2 = error2 * observer.features.pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)];
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
  result.points = static_cast<int>(point_storage.size());
  result.observations = static_cast<int>(observations.size());
  result.initial_rms_px = rms();
  if (free_kfs.empty() || observations.empty()) return result;

  for (Observation& obs : observations) {  // a point behind an observer cannot enter the problem
    double chi2 = 0.0;
    obs.inlier = chi2_of(obs, chi2);
  }
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // one manifold shared by all poses
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // `costs` above
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // the two losses above
  problem_options.enable_fast_removal = true;                         // outliers leave between passes
  ceres::Problem problem(problem_options);
  build_problem(problem);

  StopCallback stop_callback(options.stop_requested);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.num_threads = options.num_threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.callbacks.push_back(&stop_callback);
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (Eigen::Vector3d& p : point_storage) {
    if (problem.HasParameterBlock(p.data())) ordering->AddElementToGroup(p.data(), 0);
  }
  for (PoseBlock& pose : pose_storage) {
    if (problem.HasParameterBlock(pose.data())) ordering->AddElementToGroup(pose.data(), 1);
  }
  solver_options.linear_solver_ordering = ordering;
  ceres::Solver::Summary summary;

  solver_options.max_num_iterations = options.first_pass_iterations;
  ceres::Solve(solver_options, &problem, &summary);
  // As ORB-SLAM2: a stop requested during the first pass also skips the second.
  if (!stop_callback.stopped()) {
    // Second pass on the inliers of the first. ORB-SLAM2 also drops the robust kernel here; the
    // Huber kernel is kept instead (so the problem is reused, not rebuilt): every remaining residual
    // starts inside the kernel's quadratic region, where the two are identical.
    for (Observation& obs : observations) {
      double chi2 = 0.0;
      const bool inlier = chi2_of(obs, chi2) && chi2 <= obs.chi2_threshold;
      if (!inlier && obs.block != nullptr) problem.RemoveResidualBlock(obs.block);
      obs.inlier = inlier;
    }
    solver_options.max_num_iterations = options.second_pass_iterations;
    ceres::Solve(solver_options, &problem, &summary);
  }
  result.aborted = stop_callback.stopped();

  // Write back, then unlink the observations that are still outliers.
  for (const KeyframeId id : free_kfs) {
    map.keyframe(id)->T_wc = from_pose_block(pose_of(id));
    changes.changed_keyframes.insert(id);
  }
  for (const auto& [id, index] : point_index) map.point(id)->p_w = point_storage[index];
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

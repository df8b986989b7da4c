// Global bundle adjustment with Ceres over the whole map, abortable between iterations.
// GCC 12 with -march=native (AVX-512) reports Eigen's vectorised quaternion reductions as "may be used
// uninitialized": a known false positive (bundle_adjustment_terms.cpp, inertial_bundle_adjustment.cpp).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "components/core/loop/global_bundle_adjustment.hpp"

#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>

#include <ceres/ceres.h>

#include "components/core/imu/imu_factor.hpp"
#include "components/core/map/ids.hpp"
#include "components/core/mapping/bundle_adjustment_terms.hpp"

namespace heslam {
namespace {

class AbortCallback : public ceres::IterationCallback {
 public:
  explicit AbortCallback(const std::atomic<bool>* stop) : stop_(stop) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (stop_ != nullptr && stop_->load(std::memory_order_relaxed)) aborted_ = true;
    return aborted_ ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
  }
  bool aborted() const { return aborted_; }

 private:
  const std::atomic<bool>* stop_;
  bool aborted_ = false;
};

// Gaussian prior on a keyframe's biases around b0: (bg - bg0) / sigma_g, (ba - ba0) / sigma_a.
struct BiasPrior {
  Eigen::Vector3d bg0, ba0;
  double inv_sigma_gyro, inv_sigma_accel;
  template <typename T>
  bool operator()(const T* bg, const T* ba, T* residual) const {
    for (int k = 0; k < 3; ++k) {
      residual[k] = (bg[k] - T(bg0[k])) * T(inv_sigma_gyro);
      residual[3 + k] = (ba[k] - T(ba0[k])) * T(inv_sigma_accel);
    }
    return true;
  }
};

// A keyframe's velocity and bias blocks in the problem.
struct InertialBlocks {
  Eigen::Vector3d v, bg, ba;
};

}  // namespace

GlobalBundleAdjustmentResult GlobalBundleAdjustment::compute(const Map& map, const PinholeStereo& camera,
                                                             const std::atomic<bool>* stop,
                                                             const GlobalInertialInput* inertial) const {
  const auto start = std::chrono::steady_clock::now();
  GlobalBundleAdjustmentResult result;

  // Contiguous parameters in id order (Ceres orders blocks by address: reproducible solves).
  std::vector<PoseBlock> poses;
  std::vector<MapId> pose_maps;
  std::map<KeyframeId, std::size_t> pose_index;
  for (const auto& [id, kf] : map.keyframes) {
    if (kf.culled) continue;
    pose_index[id] = poses.size();
    poses.push_back(to_pose_block(kf.T_wc));
    pose_maps.push_back(kf.map_id);
  }
  std::vector<Eigen::Vector3d> points;
  std::vector<PointId> point_ids;
  for (const auto& [id, point] : map.points) {
    if (point.culled) continue;
    point_ids.push_back(id);
    points.push_back(point.p_w);
  }

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // one manifold shared by all poses
  ceres::Problem problem(problem_options);
  PoseManifold pose_manifold;
  for (std::size_t p = 0; p < point_ids.size(); ++p) {
    for (const auto& [kf_id, index] : map.point(point_ids[p])->observations) {
      const auto pose = pose_index.find(kf_id);
      if (pose == pose_index.end()) continue;
      const Keyframe& kf = map.keyframes.at(kf_id);
      const std::size_t i = static_cast<std::size_t>(index);
      // Behind the camera at the start: the residual cannot be evaluated, leave it out.
      if (transform_to_camera(poses[pose->second], points[p]).z() <= 0.0) continue;
      const Keypoint& kp = kf.features.keypoints[i];
      const bool stereo = kf.features.has_stereo(i);
      const double inv_sigma = std::sqrt(kf.features.pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)]);
      // Ceres owns cost and loss (the problem's default ownership).
      auto* cost = new ReprojectionCost(camera, kp.u_px, kp.v_px, stereo ? kf.features.u_right_px[i] : 0.0, inv_sigma,
                                        stereo, options_.disparity_sigma_ratio);
      auto* loss = new ceres::HuberLoss(std::sqrt(stereo ? options_.stereo_chi2 : options_.mono_chi2));
      problem.AddResidualBlock(cost, loss, poses[pose->second].data(), points[p].data());
      ++result.stats.observations;
    }
  }
  // Inertial runs: a velocity and biases per keyframe of the IMU chain, an IMU factor and a bias random
  // walk between consecutive ones (std::map: the blocks' addresses stay put).
  std::map<KeyframeId, InertialBlocks> inertial_blocks;
  Eigen::Vector3d gravity_w = inertial != nullptr ? inertial->gravity_w : Eigen::Vector3d::Zero();
  if (inertial != nullptr) {
    const auto blocks_of = [&](KeyframeId id) -> InertialBlocks& {
      const auto state = inertial->states.find(id);
      if (state == inertial->states.end()) {
        throw std::invalid_argument("GlobalBundleAdjustment: IMU interval keyframe " + format_id(id) +
                                    " has no inertial state");
      }
      auto [it, inserted] = inertial_blocks.try_emplace(id);
      if (inserted) it->second = {state->second.v_wb, state->second.bias.gyro_rad_s, state->second.bias.accel_m_s2};
      return it->second;
    };
    std::set<KeyframeId> followers;  // keyframes an interval ends at: not the first of a chain
    for (const GlobalInertialInterval& interval : inertial->intervals) {
      const auto pose_i = pose_index.find(interval.from);
      const auto pose_j = pose_index.find(interval.to);
      if (pose_i == pose_index.end() || pose_j == pose_index.end()) {
        ++result.stats.imu_intervals_skipped;
        continue;
      }
      InertialBlocks& i = blocks_of(interval.from);
      InertialBlocks& j = blocks_of(interval.to);
      problem.AddResidualBlock(new ImuCameraCost(interval.preintegration, inertial->T_cb), nullptr,
                               poses[pose_i->second].data(), i.v.data(), i.bg.data(), i.ba.data(),
                               poses[pose_j->second].data(), j.v.data(), gravity_w.data());
      problem.AddResidualBlock(BiasRandomWalkFactor::create(interval.preintegration), nullptr, i.bg.data(), i.ba.data(),
                               j.bg.data(), j.ba.data());
      followers.insert(interval.to);
      ++result.stats.imu_factors;
    }
    for (auto& [id, blocks] : inertial_blocks) {
      if (followers.count(id) != 0) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<BiasPrior, 6, 3, 3>(
                                   new BiasPrior{blocks.bg, blocks.ba, 1.0 / inertial->gyro_bias_prior_stddev_rad_s,
                                                 1.0 / inertial->accel_bias_prior_stddev_m_s2}),
                               nullptr, blocks.bg.data(), blocks.ba.data());
    }
    if (!inertial_blocks.empty()) problem.SetParameterBlockConstant(gravity_w.data());
    result.stats.inertial_keyframes = static_cast<int>(inertial_blocks.size());
  }

  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (Eigen::Vector3d& point : points) {
    if (!problem.HasParameterBlock(point.data())) continue;
    ordering->AddElementToGroup(point.data(), 0);
    ++result.stats.points;
  }
  std::set<MapId> gauge_fixed;  // the atlas: no observation joins two maps, so each has a gauge of its own
  for (std::size_t k = 0; k < poses.size(); ++k) {
    PoseBlock& pose = poses[k];
    if (!problem.HasParameterBlock(pose.data())) continue;
    problem.SetManifold(pose.data(), &pose_manifold);
    ordering->AddElementToGroup(pose.data(), 1);
    if (gauge_fixed.insert(pose_maps[k]).second) {  // the oldest keyframe of its map in the problem anchors it
      problem.SetParameterBlockConstant(pose.data());
    }
    ++result.stats.keyframes;
  }
  for (auto& [id, blocks] : inertial_blocks) {
    for (double* block : {blocks.v.data(), blocks.bg.data(), blocks.ba.data()}) ordering->AddElementToGroup(block, 1);
  }
  if (!inertial_blocks.empty()) ordering->AddElementToGroup(gravity_w.data(), 1);

  if (result.stats.observations > 0 || result.stats.imu_factors > 0) {
    AbortCallback abort_callback(stop);
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::SPARSE_SCHUR;
    solver_options.linear_solver_ordering = ordering;
    solver_options.max_num_iterations = options_.max_iterations;
    solver_options.num_threads = options_.num_threads;
    solver_options.logging_type = ceres::SILENT;
    solver_options.callbacks.push_back(&abort_callback);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    result.stats.aborted = abort_callback.aborted();
    result.stats.initial_cost = summary.initial_cost;
    result.stats.final_cost = summary.final_cost;
    result.stats.iterations = static_cast<int>(summary.iterations.size()) - 1;  // entry 0 is the start
  }

  for (const auto& [id, index] : pose_index) {
    const double* pose = poses[index].data();
    const bool moved = problem.HasParameterBlock(pose) && !problem.IsParameterBlockConstant(pose);
    result.corrected_T_wc.emplace_back(id, moved ? from_pose_block(poses[index]) : map.keyframes.at(id).T_wc);
  }
  for (std::size_t p = 0; p < point_ids.size(); ++p) {
    if (problem.HasParameterBlock(points[p].data())) result.p_w.emplace_back(point_ids[p], points[p]);
  }
  for (const auto& [id, blocks] : inertial_blocks) {
    InertialKeyframeState& state = result.states[id];
    state.v_wb = blocks.v;
    state.bias.gyro_rad_s = blocks.bg;
    state.bias.accel_m_s2 = blocks.ba;
  }
  result.stats.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace heslam

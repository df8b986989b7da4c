// Inertial local bundle adjustment (Ceres): reprojection residuals plus IMU and bias random walk factors.
// GCC 12 with -march=native (AVX-512) reports Eigen's vectorised quaternion reductions as "may be used
// uninitialized": a known false positive (bundle_adjustment_terms.cpp).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "components/core/mapping/inertial_bundle_adjustment.hpp"

#include <cmath>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>

#include <ceres/sphere_manifold.h>

#include "components/core/map/ids.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"

namespace heslam {
namespace {

struct Observation {
  KeyframeId kf_id;
  PointId point_id;
  std::size_t pose;
  std::size_t point;
  bool stereo;
  double chi2_threshold;
  double u_px, v_px, disparity_px, inv_sigma2;
  ceres::ResidualBlockId block = nullptr;
  bool inlier = true;
};

// d(Plus(x, (w, 0)))/dw at w = 0 for PoseManifold's quaternion (x y z w): Exp(w) q = q + 0.5 (w, 0) * q.
Eigen::Matrix<double, 4, 3> quaternion_plus_jacobian(const double* q) {
  const Eigen::Vector3d v(q[0], q[1], q[2]);
  const double w = q[3];
  Eigen::Matrix3d skew_v;
  skew_v << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  Eigen::Matrix<double, 4, 3> J;
  J.topRows<3>() = 0.5 * (w * Eigen::Matrix3d::Identity() - skew_v);
  J.row(3) = -0.5 * v.transpose();
  return J;
}

// Prior on the direction of gravity: (g - g0) / (|g0| sigma), g on the sphere of radius |g0|.
struct GravityPrior {
  Eigen::Vector3d g0;
  double inv_sigma;
  template <typename T>
  bool operator()(const T* g, T* residual) const {
    for (int k = 0; k < 3; ++k) residual[k] = (g[k] - T(g0[k])) * T(inv_sigma);
    return true;
  }
};

bool finite(const PoseBlock& block) {
  for (const double x : block) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

}  // namespace

ImuCameraCost::ImuCameraCost(const ImuPreintegration& preintegration, const Pose3& T_cb)
    : autodiff_(new Functor{ImuIntervalResidual(preintegration), T_cb.linear(), T_cb.translation()}) {}

bool ImuCameraCost::Evaluate(const double* const* parameters, double* residuals, double** jacobians) const {
  if (jacobians == nullptr) return autodiff_.Evaluate(parameters, residuals, nullptr);
  // Ambient (quaternion) Jacobians from autodiff, then chained with PoseManifold's Plus at zero.
  Eigen::Matrix<double, 9, 7, Eigen::RowMajor> ambient_i, ambient_j;
  double* inner[7] = {jacobians[0] != nullptr ? ambient_i.data() : nullptr, jacobians[1], jacobians[2], jacobians[3],
                      jacobians[4] != nullptr ? ambient_j.data() : nullptr, jacobians[5], jacobians[6]};
  if (!autodiff_.Evaluate(parameters, residuals, inner)) return false;
  for (const int block : {0, 4}) {
    if (jacobians[block] == nullptr) continue;
    const auto& ambient = block == 0 ? ambient_i : ambient_j;
    Eigen::Map<Eigen::Matrix<double, 9, 7, Eigen::RowMajor>> J(jacobians[block]);
    J.leftCols<3>() = ambient.leftCols<4>() * quaternion_plus_jacobian(parameters[block]);
    J.middleCols<3>(3) = ambient.middleCols<3>(4);
    J.col(6).setZero();
  }
  return true;
}

InertialBundleAdjustmentResult inertial_local_bundle_adjustment(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                                const LocalBundleAdjustmentOptions& options,
                                                                InertialWindow& window, MapChanges& changes) {
  InertialBundleAdjustmentResult result;
  if (window.chain.size() < 2 || window.intervals.size() + 1 != window.chain.size()) {
    throw std::invalid_argument("inertial_local_bundle_adjustment: " + std::to_string(window.chain.size()) +
                                " chain keyframes and " + std::to_string(window.intervals.size()) +
                                " intervals (expected at least 2 and one fewer)");
  }
  for (const KeyframeId id : window.chain) {
    const Keyframe* chain_kf = map.keyframe(id);
    if (chain_kf == nullptr || chain_kf->culled || window.states.count(id) == 0) {
      throw std::invalid_argument("inertial_local_bundle_adjustment: chain keyframe " + format_id(id) +
                                  (window.states.count(id) == 0 ? " has no inertial state" : " is not in the map"));
    }
  }
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled || map.keyframes.empty()) return result;
  const KeyframeId origin_id = map.keyframes.begin()->first;
  const KeyframeId anchor_id = window.chain.front();

  std::set<KeyframeId> free_kfs{kf_id};
  for (const auto& [neighbour, weight] : kf->covisible) {
    const Keyframe* other = map.keyframe(neighbour);
    if (other != nullptr && !other->culled) free_kfs.insert(neighbour);
  }
  for (std::size_t k = 1; k < window.chain.size(); ++k) free_kfs.insert(window.chain[k]);
  free_kfs.erase(anchor_id);
  std::set<PointId> point_ids;
  for (const KeyframeId id : free_kfs) {
    for (const PointId point_id : map.keyframe(id)->point_ids) {
      if (point_id != kNoId && map.point(point_id) != nullptr) point_ids.insert(point_id);
    }
  }
  std::set<KeyframeId> fixed_kfs{anchor_id};
  for (const PointId point_id : point_ids) {
    for (const auto& [observer, index] : map.point(point_id)->observations) {
      if (free_kfs.count(observer) == 0) fixed_kfs.insert(observer);
    }
  }
  if (free_kfs.count(origin_id) != 0) {
    free_kfs.erase(origin_id);
    fixed_kfs.insert(origin_id);
  }

  std::map<KeyframeId, std::size_t> pose_index;
  std::vector<PoseBlock> poses;
  for (const auto& [id, unused] : map.keyframes) {
    if (free_kfs.count(id) == 0 && fixed_kfs.count(id) == 0) continue;
    pose_index[id] = poses.size();
    poses.push_back(to_pose_block(map.keyframe(id)->T_wc));
  }
  std::map<PointId, std::size_t> point_index;
  std::vector<Eigen::Vector3d> points;
  for (const PointId id : point_ids) {
    point_index[id] = points.size();
    points.push_back(map.point(id)->p_w);
  }

  std::vector<Observation> observations;
  for (const PointId point_id : point_ids) {
    for (const auto& [observer, index] : map.point(point_id)->observations) {
      const Keyframe* observer_kf = map.keyframe(observer);
      const auto pose = pose_index.find(observer);
      if (observer_kf == nullptr || pose == pose_index.end()) continue;
      const std::size_t i = static_cast<std::size_t>(index);
      const StereoFeatures& features = observer_kf->features;
      const Keypoint& kp = features.keypoints[i];
      const bool stereo = features.has_stereo(i);
      Observation obs{observer,
                      point_id,
                      pose->second,
                      point_index.at(point_id),
                      stereo,
                      stereo ? options.stereo_chi2 : options.mono_chi2,
                      kp.u_px,
                      kp.v_px,
                      stereo ? kp.u_px - features.u_right_px[i] : 0.0,
                      features.pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)]};
      observations.push_back(obs);
    }
  }
  const auto chi2_of = [&](const Observation& obs, double& chi2) {
    const Eigen::Vector3d pc = transform_to_camera(poses[obs.pose], points[obs.point]);
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
  LocalBundleAdjustmentResult& visual = result.visual;
  visual.free_keyframes = static_cast<int>(free_kfs.size());
  visual.fixed_keyframes = static_cast<int>(fixed_kfs.size());
  visual.points = static_cast<int>(points.size());
  visual.observations = static_cast<int>(observations.size());
  visual.initial_rms_px = rms();
  if (free_kfs.empty()) return result;

  PoseManifold pose_manifold;  // both outlive the problem (not owned by it)
  ceres::SphereManifold<3> sphere;
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = true;
  ceres::Problem problem(problem_options);
  for (Observation& obs : observations) {
    double chi2 = 0.0;
    obs.inlier = chi2_of(obs, chi2);  // a point behind an observer cannot enter the problem
    if (!obs.inlier) continue;
    const double inv_sigma = std::sqrt(static_cast<float>(obs.inv_sigma2));
    auto* cost = new ReprojectionCost(camera, obs.u_px, obs.v_px, obs.u_px - obs.disparity_px, inv_sigma, obs.stereo,
                                      options.disparity_sigma_ratio);
    obs.block = problem.AddResidualBlock(cost, new ceres::HuberLoss(std::sqrt(obs.chi2_threshold)),
                                         poses[obs.pose].data(), points[obs.point].data());
  }

  // Inertial blocks, one set per chain keyframe.
  struct Inertial {
    Eigen::Vector3d v, bg, ba;
  };
  std::vector<Inertial> inertial(window.chain.size());
  for (std::size_t k = 0; k < window.chain.size(); ++k) {
    const InertialKeyframeState& state = window.states.at(window.chain[k]);
    inertial[k] = {state.v_wb, state.bias.gyro_rad_s, state.bias.accel_m_s2};
  }
  Eigen::Vector3d gravity_w = window.gravity_w;
  for (std::size_t k = 0; k + 1 < window.chain.size(); ++k) {
    PoseBlock& pose_i = poses[pose_index.at(window.chain[k])];
    PoseBlock& pose_j = poses[pose_index.at(window.chain[k + 1])];
    problem.AddResidualBlock(new ImuCameraCost(window.intervals[k], window.T_cb), nullptr, pose_i.data(),
                             inertial[k].v.data(), inertial[k].bg.data(), inertial[k].ba.data(), pose_j.data(),
                             inertial[k + 1].v.data(), gravity_w.data());
    problem.AddResidualBlock(BiasRandomWalkFactor::create(window.intervals[k]), nullptr, inertial[k].bg.data(),
                             inertial[k].ba.data(), inertial[k + 1].bg.data(), inertial[k + 1].ba.data());
    ++result.imu_factors;
  }
  if (window.hold_anchor) {
    problem.SetParameterBlockConstant(inertial[0].v.data());
    problem.SetParameterBlockConstant(inertial[0].bg.data());
    problem.SetParameterBlockConstant(inertial[0].ba.data());
  }
  result.inertial_keyframes = static_cast<int>(window.chain.size()) - (window.hold_anchor ? 1 : 0);
  if (window.gravity_stddev_rad > 0.0) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<GravityPrior, 3, 3>(new GravityPrior{
                                 window.gravity_w, 1.0 / (window.gravity_w.norm() * window.gravity_stddev_rad)}),
                             nullptr, gravity_w.data());
    problem.SetManifold(gravity_w.data(), &sphere);
  } else {
    problem.SetParameterBlockConstant(gravity_w.data());
  }

  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (Eigen::Vector3d& point : points) {
    if (problem.HasParameterBlock(point.data())) ordering->AddElementToGroup(point.data(), 0);
  }
  for (const auto& [id, index] : pose_index) {
    double* pose = poses[index].data();
    if (!problem.HasParameterBlock(pose)) continue;
    problem.SetManifold(pose, &pose_manifold);
    ordering->AddElementToGroup(pose, 1);
    if (free_kfs.count(id) == 0) problem.SetParameterBlockConstant(pose);
  }
  for (Inertial& state : inertial) {
    for (double* block : {state.v.data(), state.bg.data(), state.ba.data()}) ordering->AddElementToGroup(block, 1);
  }
  ordering->AddElementToGroup(gravity_w.data(), 1);

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.linear_solver_ordering = ordering;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.max_num_iterations = options.first_pass_iterations;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  result.initial_cost = summary.initial_cost;
  bool usable = summary.termination_type != ceres::FAILURE && std::isfinite(summary.final_cost);
  if (usable && options.second_pass_iterations > 0) {
    for (Observation& obs : observations) {
      if (obs.block == nullptr) continue;
      double chi2 = 0.0;
      obs.inlier = chi2_of(obs, chi2) && chi2 <= obs.chi2_threshold;
      if (!obs.inlier) {
        problem.RemoveResidualBlock(obs.block);
        obs.block = nullptr;
      }
    }
    solver_options.max_num_iterations = options.second_pass_iterations;
    ceres::Solve(solver_options, &problem, &summary);
    usable = summary.termination_type != ceres::FAILURE && std::isfinite(summary.final_cost);
  }
  result.final_cost = summary.final_cost;
  for (const KeyframeId id : free_kfs) usable = usable && finite(poses[pose_index.at(id)]);
  for (const Inertial& state : inertial)
    usable = usable && state.v.allFinite() && state.bg.allFinite() && state.ba.allFinite();
  for (const Eigen::Vector3d& point : points) usable = usable && point.allFinite();
  usable = usable && gravity_w.allFinite();
  if (!usable) return result;  // nothing written back: the caller falls back to the visual BA
  result.solved = true;

  for (const KeyframeId id : free_kfs) {
    map.keyframe(id)->T_wc = from_pose_block(poses[pose_index.at(id)]);
    changes.changed_keyframes.insert(id);
  }
  for (std::size_t k = window.hold_anchor ? 1 : 0; k < window.chain.size(); ++k) {
    InertialKeyframeState& state = window.states.at(window.chain[k]);
    state.v_wb = inertial[k].v;
    state.bias.gyro_rad_s = inertial[k].bg;
    state.bias.accel_m_s2 = inertial[k].ba;
  }
  for (const auto& [id, index] : point_index) map.point(id)->p_w = points[index];
  window.gravity_w = gravity_w;
  for (Observation& obs : observations) {
    double chi2 = 0.0;
    obs.inlier = chi2_of(obs, chi2) && chi2 <= obs.chi2_threshold;
  }
  visual.final_rms_px = rms();
  for (const Observation& obs : observations) {
    if (obs.inlier || map.point(obs.point_id) == nullptr) continue;
    erase_observation(map, obs.point_id, obs.kf_id);
    ++visual.outliers_removed;
    changes.changed_keyframes.insert(obs.kf_id);
    if (observation_weight(map, *map.point(obs.point_id)) <= 2) {  // ORB-SLAM2: too weakly observed to keep
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

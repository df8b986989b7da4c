// The residual radial refit of a saved map (lens_refit.hpp).
#include "tools/bench/lens_refit/lens_refit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

namespace heslam::bench {
namespace {

// ORB-SLAM2's chi2 thresholds (95 %, 2 and 3 dof) as Huber thresholds on the whitened residual.
constexpr double kMonoHuber = 2.447651936;  // sqrt(5.991)
constexpr double kStereoHuber = 2.795534;   // sqrt(7.815)
constexpr double kMinDepthM = 0.01;         // behind or at the camera: no residual

using AngleAxisPose = std::array<double, 6>;  // angle-axis of R_cw, then t_cw

struct Observation {
  int pose = 0;
  int point = 0;
  double u_px = 0.0, v_px = 0.0, disparity_px = 0.0;
  double inv_sigma = 1.0;
  bool stereo = false;
};

struct RefitProblem {
  std::vector<AngleAxisPose> poses;  // stamp order; the first is held fixed (gauge)
  std::vector<Eigen::Vector3d> points;
  std::vector<Observation> observations;
};

struct RadialReprojection {
  PinholeStereo camera;
  Observation obs;
  double disparity_weight;

  template <typename T>
  bool operator()(const T* pose, const T* p_w, const T* radial_k, T* residual) const {
    T p_c[3];
    ceres::AngleAxisRotatePoint(pose, p_w, p_c);
    for (int i = 0; i < 3; ++i) p_c[i] += pose[3 + i];
    const int n = obs.stereo ? 3 : 2;
    if (p_c[2] < T(kMinDepthM)) {
      for (int i = 0; i < n; ++i) residual[i] = T(0);
      return true;
    }
    const T x = p_c[0] / p_c[2];
    const T y = p_c[1] / p_c[2];
    const T s = T(1) + radial_k[0] * (x * x + y * y);
    const T u = camera.fx_px * x * s + camera.cx_px;
    const T v = camera.fy_px * y * s + camera.cy_px;
    residual[0] = (u - obs.u_px) * obs.inv_sigma;
    residual[1] = (v - obs.v_px) * obs.inv_sigma;
    if (obs.stereo) {
      const T x_right = x - camera.baseline_m / p_c[2];
      const T u_right = camera.fx_px * x_right * (T(1) + radial_k[0] * (x_right * x_right + y * y)) + camera.cx_px;
      residual[2] = ((u - u_right) - obs.disparity_px) * obs.inv_sigma * disparity_weight;
    }
    return true;
  }
};

AngleAxisPose to_angle_axis(const Pose3& T_wc) {
  const Pose3 T_cw = T_wc.inverse();
  const Eigen::Matrix3d R = T_cw.rotation();
  AngleAxisPose pose{};
  ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(R.data()), pose.data());
  for (int i = 0; i < 3; ++i) pose[3 + i] = T_cw.translation()[i];
  return pose;
}

Eigen::Vector3d camera_centre(const AngleAxisPose& pose) {
  Eigen::Matrix3d R_cw;
  ceres::AngleAxisToRotationMatrix(pose.data(), ceres::ColumnMajorAdapter3x3(R_cw.data()));
  return -R_cw.transpose() * Eigen::Vector3d(pose[3], pose[4], pose[5]);
}

double path_length_m(const std::vector<AngleAxisPose>& poses) {
  double length = 0.0;
  for (std::size_t i = 1; i < poses.size(); ++i)
    length += (camera_centre(poses[i]) - camera_centre(poses[i - 1])).norm();
  return length;
}

RefitProblem build_problem(const Map& map, const LensRefitOptions& options, LensRefitResult& counts) {
  std::vector<const Keyframe*> live;
  for (const auto& [id, keyframe] : map.keyframes)
    if (!keyframe.culled) live.push_back(&keyframe);
  std::stable_sort(live.begin(), live.end(),
                   [](const Keyframe* a, const Keyframe* b) { return a->stamp_ns < b->stamp_ns; });
  const auto count = static_cast<double>(live.size());
  const auto first = static_cast<std::size_t>(std::clamp(options.first_fraction, 0.0, 1.0) * count);
  const auto last = static_cast<std::size_t>(std::clamp(options.last_fraction, 0.0, 1.0) * count);

  RefitProblem problem;
  std::map<KeyframeId, int> pose_of;
  for (std::size_t i = first; i < last; ++i) {
    pose_of[live[i]->id] = static_cast<int>(problem.poses.size());
    problem.poses.push_back(to_angle_axis(live[i]->T_wc));
  }
  if (problem.poses.size() < 2)
    throw std::invalid_argument("lens refit: the window holds " + std::to_string(problem.poses.size()) +
                                " keyframes; at least 2 are needed");

  for (const auto& [id, point] : map.points) {
    if (point.culled || point.merged_into != kNoId) continue;
    std::vector<Observation> observations;
    for (const auto& [keyframe_id, index] : point.observations) {
      const auto pose = pose_of.find(keyframe_id);
      if (pose == pose_of.end()) continue;
      const StereoFeatures& features = map.keyframe(keyframe_id)->features;
      if (index < 0 || static_cast<std::size_t>(index) >= features.size() ||
          features.keypoints[index].octave >= static_cast<int>(features.pyramid.scale.size())) {
        ++counts.skipped_observations;
        continue;
      }
      const Keypoint& keypoint = features.keypoints[index];
      Observation obs;
      obs.pose = pose->second;
      obs.point = static_cast<int>(problem.points.size());
      obs.u_px = keypoint.u_px;
      obs.v_px = keypoint.v_px;
      obs.stereo = features.has_stereo(index);
      obs.disparity_px = obs.stereo ? keypoint.u_px - features.u_right_px[index] : 0.0;
      obs.inv_sigma = 1.0 / features.pyramid.scale[keypoint.octave];
      observations.push_back(obs);
    }
    if (observations.size() < 2) continue;
    for (const Observation& obs : observations) counts.stereo_observations += obs.stereo ? 1 : 0;
    problem.observations.insert(problem.observations.end(), observations.begin(), observations.end());
    problem.points.push_back(point.p_w);
  }
  if (problem.points.empty()) throw std::invalid_argument("lens refit: no map point is observed twice in the window");
  counts.keyframes = static_cast<int>(problem.poses.size());
  counts.points = static_cast<int>(problem.points.size());
  counts.observations = static_cast<int>(problem.observations.size());
  return problem;
}

struct Solution {
  double cost = 0.0;
  double radial_k = 0.0;
  double path_m = 0.0;
  int residuals = 0;
  int parameters = 0;
};

// Solves a copy of `problem`; radial_k starts at `radial_k` and is estimated when `free_k`.
Solution solve(const RefitProblem& problem, const PinholeStereo& camera, const LensRefitOptions& options,
               double radial_k, bool free_k) {
  std::vector<AngleAxisPose> poses = problem.poses;
  std::vector<Eigen::Vector3d> points = problem.points;
  double k = radial_k;
  ceres::Problem ceres_problem;
  Solution solution;
  for (const Observation& obs : problem.observations) {
    const int n = obs.stereo ? 3 : 2;
    auto* cost = new ceres::AutoDiffCostFunction<RadialReprojection, ceres::DYNAMIC, 6, 3, 1>(
        new RadialReprojection{camera, obs, 1.0 / options.disparity_sigma_ratio}, n);
    ceres_problem.AddResidualBlock(cost, new ceres::HuberLoss(obs.stereo ? kStereoHuber : kMonoHuber),
                                   poses[obs.pose].data(), points[obs.point].data(), &k);
    solution.residuals += n;
  }
  ceres_problem.SetParameterBlockConstant(poses.front().data());
  if (!free_k) ceres_problem.SetParameterBlockConstant(&k);
  solution.parameters = 6 * static_cast<int>(poses.size() - 1) + 3 * static_cast<int>(points.size()) + (free_k ? 1 : 0);

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_SCHUR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.num_threads = 1;  // deterministic
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &ceres_problem, &summary);
  solution.cost = summary.final_cost;
  solution.radial_k = k;
  solution.path_m = path_length_m(poses);
  return solution;
}

}  // namespace

LensRefitResult refit_residual_radial(const Map& map, const PinholeStereo& camera, const LensRefitOptions& options) {
  LensRefitResult result;
  const RefitProblem problem = build_problem(map, options, result);
  const Solution at_zero = solve(problem, camera, options, 0.0, false);
  const Solution free = solve(problem, camera, options, 0.0, true);
  result.cost_at_zero = at_zero.cost;
  result.path_m_at_zero = at_zero.path_m;
  result.cost_free = free.cost;
  result.path_m_free = free.path_m;
  result.radial_k = free.radial_k;

  // cost(k* + h) ~ cost(k*) + h^2 / (2 sigma^2) for unit-variance residuals; the reduced chi-square
  // rescales that to the residuals' actual spread.
  const double h = options.sigma_step;
  const double above = solve(problem, camera, options, free.radial_k + h, false).cost;
  const double below = solve(problem, camera, options, free.radial_k - h, false).cost;
  const double rise = std::max(0.5 * (above + below) - free.cost, 1e-12);
  const int dof = std::max(free.residuals - free.parameters, 1);
  const double reduced_chi2 = 2.0 * free.cost / dof;
  result.radial_k_sigma = h / std::sqrt(2.0 * rise) * std::sqrt(reduced_chi2);
  return result;
}

std::vector<LensRefitProfilePoint> refit_profile(const Map& map, const PinholeStereo& camera,
                                                 const LensRefitOptions& options,
                                                 const std::vector<double>& radial_ks) {
  LensRefitResult counts;
  const RefitProblem problem = build_problem(map, options, counts);
  std::vector<LensRefitProfilePoint> profile;
  for (double k : radial_ks) {
    const Solution solution = solve(problem, camera, options, k, false);
    profile.push_back({k, solution.cost, solution.path_m});
  }
  return profile;
}

}  // namespace heslam::bench

// Motion-only bundle adjustment with Ceres: pose as angle-axis + translation of T_cw.
#include "components/core/tracking/motion_only_ba.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

namespace heslam {
namespace {

// Fewer residuals than this and another round cannot classify anything reliably (ORB-SLAM2 stops too).
constexpr int kMinEdgesToContinue = 10;

template <typename T>
void transform_point(const T* pose, const Eigen::Vector3d& p_w, T* p_c) {
  const T p[3] = {T(p_w.x()), T(p_w.y()), T(p_w.z())};
  ceres::AngleAxisRotatePoint(pose, p, p_c);
  p_c[0] += pose[3];
  p_c[1] += pose[4];
  p_c[2] += pose[5];
}

// Whitened reprojection error: residuals are pixel errors times 1 / sigma of the keypoint's level.
struct MonoResidual {
  MonoResidual(const PinholeStereo& camera, const PoseObservation& obs) : camera_(camera), obs_(obs) {
    sqrt_info_ = std::sqrt(obs.inv_sigma2);
  }
  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    T p_c[3];
    transform_point(pose, obs_.p_w, p_c);
    const T inv_z = T(1.0) / p_c[2];
    residual[0] = (T(camera_.fx_px) * p_c[0] * inv_z + T(camera_.cx_px) - T(obs_.u_px)) * T(sqrt_info_);
    residual[1] = (T(camera_.fy_px) * p_c[1] * inv_z + T(camera_.cy_px) - T(obs_.v_px)) * T(sqrt_info_);
    return true;
  }
  PinholeStereo camera_;
  PoseObservation obs_;
  double sqrt_info_ = 1.0;
};

// Stereo: (u, v) as mono plus the disparity error, whitened by its own sigma (a fraction of the
// keypoint's). Disparity comes from SAD subpixel refinement and is more precise than the keypoint
// position; a u_right residual would repeat the u error in the third component (u_right = u - d).
struct StereoResidual {
  StereoResidual(const PinholeStereo& camera, const PoseObservation& obs, double disparity_sigma_ratio)
      : camera_(camera), obs_(obs) {
    sqrt_info_ = std::sqrt(obs.inv_sigma2);
    disparity_sqrt_info_ = sqrt_info_ / disparity_sigma_ratio;
  }
  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    T p_c[3];
    transform_point(pose, obs_.p_w, p_c);
    const T inv_z = T(1.0) / p_c[2];
    const T u = T(camera_.fx_px) * p_c[0] * inv_z + T(camera_.cx_px);
    residual[0] = (u - T(obs_.u_px)) * T(sqrt_info_);
    residual[1] = (T(camera_.fy_px) * p_c[1] * inv_z + T(camera_.cy_px) - T(obs_.v_px)) * T(sqrt_info_);
    residual[2] = (T(camera_.bf()) * inv_z - T(obs_.u_px - obs_.u_right_px)) * T(disparity_sqrt_info_);
    return true;
  }
  PinholeStereo camera_;
  PoseObservation obs_;
  double sqrt_info_ = 1.0;
  double disparity_sqrt_info_ = 1.0;
};

void pose_to_params(const Pose3& T_cw, double* params) {
  const Eigen::Matrix3d R = T_cw.rotation();
  ceres::RotationMatrixToAngleAxis(ceres::ColumnMajorAdapter3x3(R.data()), params);
  params[3] = T_cw.translation().x();
  params[4] = T_cw.translation().y();
  params[5] = T_cw.translation().z();
}

Pose3 params_to_pose(const double* params) {
  Eigen::Matrix3d R;
  ceres::AngleAxisToRotationMatrix(params, ceres::ColumnMajorAdapter3x3(R.data()));
  Pose3 T = Pose3::Identity();
  T.linear() = R;
  T.translation() = Eigen::Vector3d(params[3], params[4], params[5]);
  return T;
}

}  // namespace

double observation_chi2(const PinholeStereo& camera, const PoseObservation& obs, const Pose3& T_cw,
                        double disparity_sigma_ratio) {
  const Eigen::Vector3d p_c = T_cw * obs.p_w;
  if (p_c.z() <= 0.0) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d uv = camera.project(p_c);
  double e2 = (uv.x() - obs.u_px) * (uv.x() - obs.u_px) + (uv.y() - obs.v_px) * (uv.y() - obs.v_px);
  if (obs.stereo()) {
    const double disparity_error = (camera.bf() / p_c.z() - (obs.u_px - obs.u_right_px)) / disparity_sigma_ratio;
    e2 += disparity_error * disparity_error;
  }
  return e2 * obs.inv_sigma2;
}

MotionOnlyBaResult optimize_pose(const PinholeStereo& camera, const std::vector<PoseObservation>& observations,
                                 const Pose3& T_cw_guess, const MotionOnlyBaOptions& options) {
  MotionOnlyBaResult result;
  result.T_cw = T_cw_guess;
  if (!(options.disparity_sigma_ratio > 0.0)) {
    throw std::invalid_argument("MotionOnlyBaOptions.disparity_sigma_ratio: expected > 0");
  }
  result.outlier.assign(observations.size(), false);
  if (observations.empty()) return result;

  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  costs.reserve(observations.size());
  for (const PoseObservation& obs : observations) {
    if (obs.stereo()) {
      costs.emplace_back(new ceres::AutoDiffCostFunction<StereoResidual, 3, 6>(new StereoResidual(camera, obs, options.disparity_sigma_ratio)));
    } else {
      costs.emplace_back(new ceres::AutoDiffCostFunction<MonoResidual, 2, 6>(new MonoResidual(camera, obs)));
    }
  }
  ceres::HuberLoss huber_mono(std::sqrt(options.chi2_mono));
  ceres::HuberLoss huber_stereo(std::sqrt(options.chi2_stereo));

  double params[6];
  pose_to_params(T_cw_guess, params);

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;  // 6x6 normal equations: cheapest
  solver_options.max_num_iterations = options.iterations_per_round;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.num_threads = 1;

  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;

  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    ceres::Problem problem(problem_options);
    problem.AddParameterBlock(params, 6);
    int edges = 0;
    for (std::size_t i = 0; i < observations.size(); ++i) {
      if (result.outlier[i]) continue;
      ceres::LossFunction* loss = nullptr;
      if (robust) loss = observations[i].stereo() ? &huber_stereo : &huber_mono;
      problem.AddResidualBlock(costs[i].get(), loss, params);
      ++edges;
    }
    if (edges < kMinEdgesToContinue && round > 0) break;
    if (edges == 0) break;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);

    // Reclassify every observation (outliers may come back), as ORB-SLAM2 does.
    const Pose3 T_cw = params_to_pose(params);
    for (std::size_t i = 0; i < observations.size(); ++i) {
      const double threshold = observations[i].stereo() ? options.chi2_stereo : options.chi2_mono;
      result.outlier[i] = !(observation_chi2(camera, observations[i], T_cw, options.disparity_sigma_ratio) <= threshold);
    }
  }
  result.T_cw = params_to_pose(params);
  result.inliers = 0;
  for (bool o : result.outlier) result.inliers += o ? 0 : 1;
  return result;
}

}  // namespace heslam

// The local BA's own solver against Ceres: analytic Jacobians against automatic differentiation of
// the same residual, the global BA's ReprojectionCost against the same Jacobians, and the minimum
// the solver reaches against the one Ceres reaches on the same robust problem.
#include <gtest/gtest.h>

#include <random>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "components/core/mapping/bundle_adjustment_solver.hpp"

namespace heslam {
namespace {

PinholeStereo test_camera() {
  PinholeStereo camera;
  camera.fx_px = 718.856;
  camera.fy_px = 718.856;
  camera.cx_px = 607.19;
  camera.cy_px = 185.22;
  camera.baseline_m = 0.54;
  return camera;
}

// The residual of linearise_observation, written generically: the pose perturbed by Exp(w) on the
// left and r added to the translation (PoseManifold::Plus at delta = (w, r)).
struct PerturbedResidual {
  PinholeStereo camera;
  BundleAdjustmentObservation obs;
  Eigen::Matrix3d R_cw;
  Eigen::Vector3d t_cw;

  template <typename T>
  bool operator()(const T* delta, const T* p_w, T* residual) const {
    const Eigen::Matrix<T, 3, 1> p(p_w[0], p_w[1], p_w[2]);
    const Eigen::Matrix<T, 3, 1> Rp = R_cw.cast<T>() * p;
    T rotated[3];
    ceres::AngleAxisRotatePoint(delta, Rp.data(), rotated);
    const T x = rotated[0] + T(t_cw.x()) + delta[3];
    const T y = rotated[1] + T(t_cw.y()) + delta[4];
    const T z = rotated[2] + T(t_cw.z()) + delta[5];
    residual[0] = obs.weight * (camera.fx_px * x / z + camera.cx_px - obs.u_px);
    residual[1] = obs.weight * (camera.fy_px * y / z + camera.cy_px - obs.v_px);
    residual[2] = obs.stereo ? obs.disparity_weight * (camera.bf() / z - obs.disparity_px) : T(0.0);
    return true;
  }
};

TEST(BundleAdjustmentSolver, AnalyticJacobiansMatchAutomaticDifferentiation) {
  const PinholeStereo camera = test_camera();
  const Eigen::Matrix3d R_cw = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, -1.0, 0.4).normalized()).toRotationMatrix();
  const Eigen::Vector3d t_cw(0.4, -0.2, 1.5);
  const Eigen::Vector3d p_w(1.2, 0.7, 9.0);
  for (const bool stereo : {false, true}) {
    BundleAdjustmentObservation obs;
    obs.u_px = 650.0;
    obs.v_px = 200.0;
    obs.disparity_px = 40.0;
    obs.weight = 1.0 / 1.2;
    obs.disparity_weight = 2.0 / 1.2;
    obs.stereo = stereo;
    Eigen::Vector3d residual;
    Eigen::Matrix<double, 3, 6> J_pose;
    Eigen::Matrix3d J_point;
    ASSERT_TRUE(linearise_observation(camera, obs, R_cw, t_cw, p_w, residual, &J_pose, &J_point));

    ceres::AutoDiffCostFunction<PerturbedResidual, 3, 6, 3> autodiff(new PerturbedResidual{camera, obs, R_cw, t_cw});
    const double delta[6] = {0, 0, 0, 0, 0, 0};
    const double* parameters[2] = {delta, p_w.data()};
    double auto_residual[3];
    Eigen::Matrix<double, 3, 6, Eigen::RowMajor> auto_J_pose;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> auto_J_point;
    double* jacobians[2] = {auto_J_pose.data(), auto_J_point.data()};
    ASSERT_TRUE(autodiff.Evaluate(parameters, auto_residual, jacobians));
    EXPECT_LT((residual - Eigen::Vector3d(auto_residual[0], auto_residual[1], auto_residual[2])).norm(), 1e-10);
    EXPECT_LT((J_pose - auto_J_pose).norm(), 1e-8 * J_pose.norm()) << "stereo " << stereo << "\n"
                                                                   << J_pose << "\n"
                                                                   << auto_J_pose;
    EXPECT_LT((J_point - auto_J_point).norm(), 1e-8 * J_point.norm()) << "stereo " << stereo;

    // The Ceres term of the loop closer's global BA: the same residual and (tangent) Jacobians.
    Pose3 T_cw = Pose3::Identity();
    T_cw.linear() = R_cw;
    T_cw.translation() = t_cw;
    const PoseBlock block = to_pose_block(T_cw.inverse());
    ReprojectionCost cost(camera, obs.u_px, obs.v_px, obs.u_px - obs.disparity_px, obs.weight, stereo,
                          obs.weight / obs.disparity_weight);
    const int rows = stereo ? 3 : 2;
    double cost_residual[3];
    double cost_J_pose[3 * 7];
    double cost_J_point[3 * 3];
    const double* cost_parameters[2] = {block.data(), p_w.data()};
    double* cost_jacobians[2] = {cost_J_pose, cost_J_point};
    ASSERT_TRUE(cost.Evaluate(cost_parameters, cost_residual, cost_jacobians));
    for (int r = 0; r < rows; ++r) {
      EXPECT_NEAR(cost_residual[r], residual[r], 1e-9);
      for (int c = 0; c < 6; ++c) EXPECT_NEAR(cost_J_pose[7 * r + c], J_pose(r, c), 1e-7 * J_pose.norm());
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(cost_J_point[3 * r + c], J_point(r, c), 1e-7 * J_point.norm());
    }
  }
}

// Six cameras along a street looking at 300 points 4-30 m ahead; a third of the observations
// monocular, 0.5 px noise, 2 % gross outliers; camera 0 fixed, the rest and the points perturbed.
struct StreetProblem {
  BundleAdjustmentProblem problem;
  std::vector<Pose3> true_T_cw;
};

StreetProblem make_street_problem(double pixel_noise_px, double outlier_rate) {
  StreetProblem result;
  BundleAdjustmentProblem& problem = result.problem;
  problem.camera = test_camera();
  std::mt19937 rng(17);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  constexpr int kCameras = 6;
  constexpr int kPoints = 300;
  for (int i = 0; i < kCameras; ++i) {
    Pose3 T_wc = Pose3::Identity();
    T_wc.translation() = Eigen::Vector3d(0.05 * i, 0.0, 1.0 * i);
    T_wc.linear() = Eigen::AngleAxisd(0.02 * i, Eigen::Vector3d::UnitY()).toRotationMatrix();
    result.true_T_cw.push_back(T_wc.inverse());
    Pose3 noisy = T_wc;
    if (i > 0) {
      noisy.translation() += 0.05 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
      const Eigen::Vector3d w = 0.005 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
      noisy.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix() * noisy.linear();
    }
    problem.poses.push_back(to_pose_block(noisy));
    problem.pose_fixed.push_back(i == 0);
  }
  for (int j = 0; j < kPoints; ++j) {
    const Eigen::Vector3d p_w(-8.0 + 16.0 * uniform(rng), -2.0 + 4.0 * uniform(rng), 10.0 + 26.0 * uniform(rng));
    problem.points.push_back(p_w + 0.1 * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)));
    for (int i = 0; i < kCameras; ++i) {
      const Eigen::Vector3d p_c = result.true_T_cw[static_cast<std::size_t>(i)] * p_w;
      BundleAdjustmentObservation obs;
      obs.pose = i;
      obs.point = j;
      const int octave = (i + j) % 3;
      const double sigma = std::pow(1.2, octave);
      obs.u_px = problem.camera.fx_px * p_c.x() / p_c.z() + problem.camera.cx_px + sigma * pixel_noise_px * normal(rng);
      obs.v_px = problem.camera.fy_px * p_c.y() / p_c.z() + problem.camera.cy_px + sigma * pixel_noise_px * normal(rng);
      obs.stereo = (i + 2 * j) % 3 != 0;
      obs.disparity_px = problem.camera.bf() / p_c.z() + sigma * pixel_noise_px * normal(rng);
      if (uniform(rng) < outlier_rate) obs.u_px += 40.0;
      obs.weight = 1.0 / sigma;
      obs.disparity_weight = obs.weight / 0.5;
      obs.huber_delta = std::sqrt(obs.stereo ? 7.815 : 5.991);
      problem.observations.push_back(obs);
    }
  }
  return result;
}

// Ceres on the same problem (the global BA's terms, Huber loss, dense Schur), to convergence.
BundleAdjustmentProblem solve_with_ceres(BundleAdjustmentProblem problem) {
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  PoseManifold manifold;
  for (const BundleAdjustmentObservation& obs : problem.observations) {
    auto* cost = new ReprojectionCost(problem.camera, obs.u_px, obs.v_px, obs.u_px - obs.disparity_px, obs.weight,
                                      obs.stereo, obs.weight / obs.disparity_weight);
    ceres_problem.AddResidualBlock(cost, new ceres::HuberLoss(obs.huber_delta),
                                   problem.poses[static_cast<std::size_t>(obs.pose)].data(),
                                   problem.points[static_cast<std::size_t>(obs.point)].data());
  }
  for (std::size_t i = 0; i < problem.poses.size(); ++i) {
    ceres_problem.SetManifold(problem.poses[i].data(), &manifold);
    if (problem.pose_fixed[i]) ceres_problem.SetParameterBlockConstant(problem.poses[i].data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = 200;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &ceres_problem, &summary);
  return problem;
}

TEST(BundleAdjustmentSolver, ReachesTheMinimumCeresReaches) {
  StreetProblem street = make_street_problem(0.5, 0.02);
  const BundleAdjustmentProblem reference = solve_with_ceres(street.problem);
  BundleAdjustmentSolverOptions options;
  options.max_iterations = 200;
  options.function_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  const BundleAdjustmentSolverSummary summary = solve_bundle_adjustment(street.problem, options);
  EXPECT_LT(summary.final_cost, 0.2 * summary.initial_cost);  // the 2 % outliers keep part of it
  EXPECT_FALSE(summary.stopped);
  for (std::size_t i = 0; i < street.problem.poses.size(); ++i) {
    const Pose3 ours = from_pose_block(street.problem.poses[i]);
    const Pose3 theirs = from_pose_block(reference.poses[i]);
    EXPECT_LT((ours.translation() - theirs.translation()).norm(), 1e-6) << "pose " << i;
    EXPECT_LT(Eigen::AngleAxisd(ours.linear().transpose() * theirs.linear()).angle(), 1e-7) << "pose " << i;
    // And both near the truth (noise level: centimetres over a 5 m baseline).
    EXPECT_LT((ours.translation() - street.true_T_cw[i].inverse().translation()).norm(), 0.05) << "pose " << i;
  }
  EXPECT_EQ(street.problem.poses[0], reference.poses[0]);  // fixed
  for (std::size_t j = 0; j < street.problem.points.size(); ++j) {
    EXPECT_LT((street.problem.points[j] - reference.points[j]).norm(), 1e-5) << "point " << j;
  }
}

TEST(BundleAdjustmentSolver, RecoversTheTruthWithoutNoise) {
  StreetProblem street = make_street_problem(0.0, 0.0);
  BundleAdjustmentSolverOptions options;
  options.max_iterations = 50;
  const BundleAdjustmentSolverSummary summary = solve_bundle_adjustment(street.problem, options);
  EXPECT_LT(summary.final_cost, 1e-12);
  for (std::size_t i = 0; i < street.problem.poses.size(); ++i) {
    const Pose3 T_wc = from_pose_block(street.problem.poses[i]);
    EXPECT_LT((T_wc.translation() - street.true_T_cw[i].inverse().translation()).norm(), 1e-7) << "pose " << i;
  }
}

TEST(BundleAdjustmentSolver, StopRequestEndsAfterThatIterationAndInactiveObservationsAreIgnored) {
  StreetProblem street = make_street_problem(0.5, 0.0);
  int asks = 0;
  BundleAdjustmentSolverOptions options;
  options.stop_requested = [&] { return ++asks == 2; };
  const BundleAdjustmentSolverSummary stopped = solve_bundle_adjustment(street.problem, options);
  EXPECT_TRUE(stopped.stopped);
  EXPECT_EQ(stopped.iterations, 2);
  EXPECT_LT(stopped.final_cost, stopped.initial_cost);

  // Observations marked inactive do not count: corrupting them changes nothing.
  StreetProblem a = make_street_problem(0.5, 0.0);
  StreetProblem b = make_street_problem(0.5, 0.0);
  for (std::size_t k = 0; k < b.problem.observations.size(); k += 5) {
    a.problem.observations[k].active = false;
    b.problem.observations[k].active = false;
    b.problem.observations[k].u_px += 500.0;
  }
  solve_bundle_adjustment(a.problem, BundleAdjustmentSolverOptions{});
  solve_bundle_adjustment(b.problem, BundleAdjustmentSolverOptions{});
  EXPECT_EQ(a.problem.poses, b.problem.poses);
  EXPECT_EQ(a.problem.points, b.problem.points);
}

}  // namespace
}  // namespace heslam

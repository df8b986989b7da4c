// The local bundle adjustment's own sparse Levenberg-Marquardt solver (poses 6-dof, points 3-dof).
//
// Why not Ceres: a street keyframe's local BA (~20 free keyframes, ~8000 points, ~40000
// observations) spent most of its time in Ceres' general machinery, not in the arithmetic: building,
// preprocessing and destroying the problem, per-block bookkeeping of the evaluator, and the
// dynamic-size Schur eliminator (mono (2) and stereo (3) residuals are mixed, so none of Ceres'
// fixed-size specializations apply); docs/benchmarks.md at 5c1f792, "Local mapper cost, street and publish".
// This solver does the same mathematics with fixed-size blocks: the normal equations accumulated
// observation by observation (analytic Jacobians of bundle_adjustment_terms.hpp's model), the points
// eliminated by the Schur complement into a dense system over the free poses (LLT), back
// substitution, and Ceres' Levenberg-Marquardt trust-region rule for the damping.
//
// Robust kernel: Huber, applied by iteratively reweighted least squares (each residual's normal
// equations weighted by rho'(s), as g2o does in ORB-SLAM2). Poses use PoseBlock and the update of
// PoseManifold (rotation perturbed on the left, translation additively), so the loop closer's Ceres
// global BA and this solver share one parametrisation. Sequential and deterministic.
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/mapping/bundle_adjustment_terms.hpp"

namespace heslam {

struct BundleAdjustmentObservation {
  int pose = 0;   // index into BundleAdjustmentProblem::poses
  int point = 0;  // index into BundleAdjustmentProblem::points
  double u_px = 0.0;
  double v_px = 0.0;
  double disparity_px = 0.0;      // u - u_right; used when stereo
  double weight = 1.0;            // whitening of u and v: 1 / keypoint sigma
  double disparity_weight = 1.0;  // whitening of the disparity
  double huber_delta = 1.0;       // the kernel's threshold on the whitened residual's norm
  bool stereo = false;            // (u, v, disparity) or (u, v)
  bool active = true;             // inactive observations are ignored (outliers between passes)
};

// Terms besides the reprojections (the inertial local BA's IMU factors, inertial_bundle_adjustment.cpp):
// parameters of their own (`dimension()` tangent entries, appended after the free poses in the reduced
// system and never eliminated) and residuals over them and the poses, without a robust kernel (cost
// 0.5 |r|^2). The solver owns the Levenberg-Marquardt loop; the terms only evaluate and move themselves.
class BundleAdjustmentExtraTerms {
 public:
  virtual ~BundleAdjustmentExtraTerms() = default;
  virtual int dimension() const = 0;
  // 0.5 |r|^2 at `poses` and the own parameters moved by `step` (nullptr: as they are); non-finite when
  // the residuals are.
  virtual double cost(const std::vector<PoseBlock>& poses, const Eigen::VectorXd* step) const = 0;
  // Adds J^T J to H and -J^T r to b at `poses` and the own parameters: free pose i's 6 tangent entries
  // (PoseManifold's) at 6 * free_index[i] (-1: held, no entries), the own parameters from 6 * (free poses).
  virtual void linearise(const std::vector<PoseBlock>& poses, const std::vector<int>& free_index, Eigen::MatrixXd& H,
                         Eigen::VectorXd& b) const = 0;
  // An accepted step: the own parameters move by `step`.
  virtual void update(const Eigen::VectorXd& step) = 0;
  // Squared norm of the own parameters (the parameter tolerance's |x|).
  virtual double squared_norm() const = 0;
};

struct BundleAdjustmentProblem {
  PinholeStereo camera;
  std::vector<PoseBlock> poses;  // world -> camera
  std::vector<bool> pose_fixed;  // one per pose
  std::vector<Eigen::Vector3d> points;
  // Must be grouped by point (all observations of a point contiguous); the Schur elimination walks
  // them point by point.
  std::vector<BundleAdjustmentObservation> observations;
  // Optional (not owned): more terms and parameters in the same solve. nullptr: reprojections only.
  BundleAdjustmentExtraTerms* extra = nullptr;
};

struct BundleAdjustmentSolverOptions {
  int max_iterations = 10;            // successful and rejected steps, as Ceres counts them
  double function_tolerance = 1e-6;   // Ceres' default: stop when |cost change| / cost falls below
  double gradient_tolerance = 1e-10;  // Ceres' default: stop when the largest gradient entry falls below
  double parameter_tolerance = 1e-8;  // Ceres' default: stop when |step| / (|x| + tol) falls below
  double initial_trust_radius = 1e4;  // Ceres' default: damping starts at diag(J^T J) / 1e4
  // Asked after every iteration; true ends the solve there (the state reached is kept).
  std::function<bool()> stop_requested;
};

struct BundleAdjustmentSolverSummary {
  int iterations = 0;
  int successful_steps = 0;
  bool stopped = false;       // stop_requested ended it
  double initial_cost = 0.0;  // 0.5 * sum of rho(|whitened residual|^2) over active observations
  double final_cost = 0.0;
};

// Whitened residual of `obs` at the given pose and point (third entry 0 when monocular) and, when
// asked, its analytic Jacobians: d/d(pose tangent (w, r)) of PoseManifold's update and d/d(p_w); the
// third rows are 0 when monocular. False when the point is not in front of the camera.
bool linearise_observation(const PinholeStereo& camera, const BundleAdjustmentObservation& obs,
                           const Eigen::Matrix3d& R_cw, const Eigen::Vector3d& t_cw, const Eigen::Vector3d& p_w,
                           Eigen::Vector3d& residual, Eigen::Matrix<double, 3, 6>* J_pose, Eigen::Matrix3d* J_point);

// Minimises the robust cost over the free poses and all points, in place.
BundleAdjustmentSolverSummary solve_bundle_adjustment(BundleAdjustmentProblem& problem,
                                                      const BundleAdjustmentSolverOptions& options);

}  // namespace heslam

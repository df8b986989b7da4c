// A Levenberg-Marquardt on N parameters with dense N x N normal equations, stepping as Ceres' LM does
// with its default options (the Ceres versions of the solvers that use it were the reference): the
// damping scales the clamped diagonal of J^T J, a rejected step raises it and retries from the same
// linearization, an accepted one lowers it by the gain ratio. Used by the motion-only optimizations
// (motion_only_ba.cpp: the pose; inertial_pose_optimization.cpp: pose, velocity and biases).
//
// The problem says how to evaluate a trial state and how to linearize at the accepted one, so that it
// may defer the normal equations until a step is accepted (motion_only_ba.cpp does):
//   double evaluate_trial(const State& x);   the cost at x, kept as the trial
//   void accept_trial();                     the trial becomes the current linearization point
//   void normal_equations(MatrixN& H, VectorN& g);   J^T J and J^T r at the current point
//   State plus(const State& x, const VectorN& step);
//   double norm(const State& x);             the size a step is compared with (Ceres' parameter tolerance)
// The caller evaluates the start (evaluate_trial + accept_trial) and passes its cost.
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace heslam {

struct DenseLmTolerances {
  // Ceres' defaults: initial damping 1 / trust radius 1e4; stop at a relative cost decrease, a gradient
  // (max norm) or a relative step below these.
  double initial_lambda = 1e-4;
  double function_tolerance = 1e-6;
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-8;
  // Rejected steps raise the damping; beyond this the step would be negligible and the solve ends.
  double max_lambda = 1e16;
  // The damping scales the diagonal of J^T J clamped to this range (Ceres' min / max_lm_diagonal).
  double min_diagonal = 1e-6;
  double max_diagonal = 1e32;
};

// At most `iterations` steps from `x` (whose cost the problem's current linearization holds); updates x.
template <int N, typename State, typename Problem>
void dense_levenberg_marquardt(Problem& problem, State& x, double cost, int iterations,
                               const DenseLmTolerances& tol = {}) {
  using MatrixN = Eigen::Matrix<double, N, N>;
  using VectorN = Eigen::Matrix<double, N, 1>;
  double lambda = tol.initial_lambda;
  double lambda_factor = 2.0;  // grows while steps are rejected in a row (Ceres' decrease factor)
  MatrixN H;
  VectorN g;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    problem.normal_equations(H, g);
    if (g.template lpNorm<Eigen::Infinity>() <= tol.gradient_tolerance) return;
    bool accepted = false;
    while (!accepted && lambda < tol.max_lambda) {
      MatrixN damped = H;
      for (int i = 0; i < N; ++i) damped(i, i) += lambda * std::clamp(H(i, i), tol.min_diagonal, tol.max_diagonal);
      const VectorN step = damped.ldlt().solve(-g);
      if (!step.allFinite()) {
        lambda *= 10.0;
        continue;
      }
      if (step.norm() <= tol.parameter_tolerance * (problem.norm(x) + tol.parameter_tolerance)) return;
      State trial = problem.plus(x, step);
      const double new_cost = problem.evaluate_trial(trial);
      // Gain ratio: actual over predicted decrease of the Gauss-Newton model of the cost.
      const double predicted = -(step.dot(g) + 0.5 * step.dot(H * step));
      const double ratio = predicted > 0.0 ? (cost - new_cost) / predicted : -1.0;
      if (ratio > 0.0) {  // false for a non-finite cost
        accepted = true;
        x = std::move(trial);
        problem.accept_trial();
        const double decrease = cost - new_cost;
        cost = new_cost;
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
        lambda_factor = 2.0;
        if (decrease <= tol.function_tolerance * (cost + decrease)) return;
      } else {
        lambda *= lambda_factor;
        lambda_factor *= 2.0;
      }
    }
    if (!accepted) return;
  }
}

}  // namespace heslam

// Sparse Schur-complement Levenberg-Marquardt for the local bundle adjustment (see the header).
// GCC 12 with -march=native and the sanitizers reports Eigen's fixed-size reductions as "may be used
// uninitialized": a known false positive (as in bundle_adjustment_terms.cpp).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "components/core/mapping/bundle_adjustment_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

namespace heslam {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix63 = Eigen::Matrix<double, 6, 3>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Ceres' Levenberg-Marquardt constants (TrustRegionStrategy / Solver::Options defaults).
constexpr double kMinDiagonal = 1e-6;          // min_lm_diagonal: damping of directions with no curvature
constexpr double kMaxDiagonal = 1e32;          // max_lm_diagonal
constexpr double kMinRelativeDecrease = 1e-3;  // a step must achieve this share of the predicted decrease
constexpr double kMaxTrustRadius = 1e16;       // max_trust_region_radius
constexpr double kMinTrustRadius = 1e-32;      // min_trust_region_radius: below, the solve has converged

struct PoseCache {
  Eigen::Matrix3d R_cw;
  Eigen::Vector3d t_cw;
};

std::vector<PoseCache> pose_caches(const std::vector<PoseBlock>& poses) {
  std::vector<PoseCache> caches(poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const PoseBlock& p = poses[i];
    caches[i].R_cw = Eigen::Quaterniond(p[3], p[0], p[1], p[2]).normalized().toRotationMatrix();
    caches[i].t_cw = Eigen::Vector3d(p[4], p[5], p[6]);
  }
  return caches;
}

double huber_rho(double s, double delta) { return s <= delta * delta ? s : 2.0 * delta * std::sqrt(s) - delta * delta; }

// 0.5 * sum rho(s); +inf when a point is behind a camera (the step is rejected, as Ceres does).
double total_cost(const BundleAdjustmentProblem& problem, const std::vector<PoseBlock>& poses,
                  const std::vector<Eigen::Vector3d>& points) {
  const std::vector<PoseCache> caches = pose_caches(poses);
  double cost = 0.0;
  Eigen::Vector3d r;
  for (const BundleAdjustmentObservation& obs : problem.observations) {
    if (!obs.active) continue;
    const PoseCache& pose = caches[static_cast<std::size_t>(obs.pose)];
    if (!linearise_observation(problem.camera, obs, pose.R_cw, pose.t_cw, points[static_cast<std::size_t>(obs.point)],
                               r, nullptr, nullptr)) {
      return std::numeric_limits<double>::infinity();
    }
    cost += huber_rho(obs.stereo ? r.squaredNorm() : r.head<2>().squaredNorm(), obs.huber_delta);
  }
  return 0.5 * cost;
}

// The normal equations of one linearisation, in blocks.
struct NormalEquations {
  std::vector<Matrix6d> H_pp;         // per free pose
  std::vector<Vector6d> b_p;          // -gradient, per free pose
  std::vector<Eigen::Matrix3d> H_xx;  // per point
  std::vector<Eigen::Vector3d> b_x;
  std::vector<Matrix63> H_px;  // per observation (free pose only)
};

}  // namespace

bool linearise_observation(const PinholeStereo& camera, const BundleAdjustmentObservation& obs,
                           const Eigen::Matrix3d& R_cw, const Eigen::Vector3d& t_cw, const Eigen::Vector3d& p_w,
                           Eigen::Vector3d& residual, Eigen::Matrix<double, 3, 6>* J_pose, Eigen::Matrix3d* J_point) {
  const Eigen::Vector3d Rp = R_cw * p_w;
  const Eigen::Vector3d p_c = Rp + t_cw;
  if (p_c.z() <= 0.0) return false;
  const double inv_z = 1.0 / p_c.z();
  const double bf = camera.bf();
  residual.x() = obs.weight * (camera.fx_px * p_c.x() * inv_z + camera.cx_px - obs.u_px);
  residual.y() = obs.weight * (camera.fy_px * p_c.y() * inv_z + camera.cy_px - obs.v_px);
  residual.z() = obs.stereo ? obs.disparity_weight * (bf * inv_z - obs.disparity_px) : 0.0;
  if (J_pose == nullptr && J_point == nullptr) return true;
  // d residual / d p_c, whitened; the third row is zero for a monocular observation.
  const double inv_z2 = inv_z * inv_z;
  Eigen::Matrix3d J_pc;
  J_pc << obs.weight * camera.fx_px * inv_z, 0.0, -obs.weight * camera.fx_px * p_c.x() * inv_z2, 0.0,
      obs.weight * camera.fy_px * inv_z, -obs.weight * camera.fy_px * p_c.y() * inv_z2, 0.0, 0.0,
      obs.stereo ? -obs.disparity_weight * bf * inv_z2 : 0.0;
  if (J_point != nullptr) J_point->noalias() = J_pc * R_cw;
  if (J_pose != nullptr) {
    // p_c(w, r) = Exp(w) R p + t + r  =>  d/dw = -[R p]x, d/dr = I.
    Eigen::Matrix3d skew_Rp;
    skew_Rp << 0.0, -Rp.z(), Rp.y(), Rp.z(), 0.0, -Rp.x(), -Rp.y(), Rp.x(), 0.0;
    J_pose->leftCols<3>().noalias() = -J_pc * skew_Rp;
    J_pose->rightCols<3>() = J_pc;
  }
  return true;
}

BundleAdjustmentSolverSummary solve_bundle_adjustment(BundleAdjustmentProblem& problem,
                                                      const BundleAdjustmentSolverOptions& options) {
  BundleAdjustmentSolverSummary summary;
  const std::size_t num_poses = problem.poses.size();
  const std::size_t num_points = problem.points.size();
  std::vector<int> free_index(num_poses, -1);  // pose -> block of the reduced system
  int num_free = 0;
  for (std::size_t i = 0; i < num_poses; ++i) {
    if (!problem.pose_fixed[i]) free_index[i] = num_free++;
  }
  // Observations of point j: [point_begin[j], point_begin[j + 1]) after grouping.
  std::vector<std::size_t> order;  // observation indices grouped by point, stable
  std::vector<std::size_t> point_begin(num_points + 1, 0);
  for (const BundleAdjustmentObservation& obs : problem.observations)
    ++point_begin[static_cast<std::size_t>(obs.point) + 1];
  for (std::size_t j = 0; j < num_points; ++j) point_begin[j + 1] += point_begin[j];
  {
    std::vector<std::size_t> fill(point_begin.begin(), point_begin.end() - 1);
    order.resize(problem.observations.size());
    for (std::size_t k = 0; k < problem.observations.size(); ++k) {
      order[fill[static_cast<std::size_t>(problem.observations[k].point)]++] = k;
    }
  }

  BundleAdjustmentExtraTerms* const extra = problem.extra;
  const int extra_size = extra != nullptr ? extra->dimension() : 0;
  double cost = total_cost(problem, problem.poses, problem.points);
  if (extra != nullptr) cost += extra->cost(problem.poses, nullptr);
  summary.initial_cost = summary.final_cost = cost;
  if (num_free == 0 && num_points == 0 && extra_size == 0) return summary;
  if (!std::isfinite(cost)) return summary;  // the caller keeps points in front; nothing sensible to do

  const PoseManifold manifold;
  NormalEquations eq;
  eq.H_pp.resize(static_cast<std::size_t>(num_free));
  eq.b_p.resize(static_cast<std::size_t>(num_free));
  eq.H_xx.resize(num_points);
  eq.b_x.resize(num_points);
  eq.H_px.resize(problem.observations.size());
  std::vector<Vector6d> diag_p(static_cast<std::size_t>(num_free));  // clamped diag(J^T J), poses
  std::vector<Eigen::Vector3d> diag_x(num_points);
  std::vector<Eigen::Matrix3d> V_inv(num_points);
  std::vector<Vector6d> step_p(static_cast<std::size_t>(num_free));
  std::vector<Eigen::Vector3d> step_x(num_points);
  std::vector<PoseBlock> candidate_poses = problem.poses;
  std::vector<Eigen::Vector3d> candidate_points = problem.points;
  const int pose_size = 6 * num_free;
  const int reduced_size = pose_size + extra_size;
  // The extra terms' normal equations over the whole reduced system (their pose diagonal blocks and
  // gradient are folded into H_pp / b_p), the damping of their own parameters and their step.
  Eigen::MatrixXd H_extra;
  Eigen::VectorXd b_extra, diag_extra, step_extra;
  if (extra != nullptr) {
    H_extra.resize(reduced_size, reduced_size);
    b_extra.resize(reduced_size);
    diag_extra.resize(extra_size);
    step_extra.setZero(extra_size);
  }
  Eigen::MatrixXd S(reduced_size, reduced_size);
  Eigen::VectorXd rhs(reduced_size);
  Eigen::LLT<Eigen::MatrixXd> llt(reduced_size);

  double radius = options.initial_trust_radius;
  double decrease_factor = 2.0;
  bool linearised = false;
  double gradient_max = 0.0;

  const auto linearise = [&]() {
    const std::vector<PoseCache> caches = pose_caches(problem.poses);
    for (auto& h : eq.H_pp) h.setZero();
    for (auto& b : eq.b_p) b.setZero();
    for (auto& h : eq.H_xx) h.setZero();
    for (auto& b : eq.b_x) b.setZero();
    for (std::size_t k = 0; k < problem.observations.size(); ++k) {
      const BundleAdjustmentObservation& obs = problem.observations[k];
      if (!obs.active) continue;
      const std::size_t pose = static_cast<std::size_t>(obs.pose);
      const std::size_t point = static_cast<std::size_t>(obs.point);
      const PoseCache& T = caches[pose];
      const int f = free_index[pose];
      Eigen::Vector3d r;
      Eigen::Matrix3d J_x;
      Eigen::Matrix<double, 3, 6> J_p;
      // In front: the current state passed total_cost.
      linearise_observation(problem.camera, obs, T.R_cw, T.t_cw, problem.points[point], r, f < 0 ? nullptr : &J_p,
                            &J_x);
      // IRLS weight of the Huber kernel: rho'(s).
      const double s = r.squaredNorm();
      const double w = s <= obs.huber_delta * obs.huber_delta ? 1.0 : obs.huber_delta / std::sqrt(s);
      eq.H_xx[point].noalias() += w * J_x.transpose() * J_x;
      eq.b_x[point].noalias() -= w * J_x.transpose() * r;
      if (f < 0) continue;
      const std::size_t fi = static_cast<std::size_t>(f);
      eq.H_pp[fi].noalias() += w * J_p.transpose() * J_p;
      eq.b_p[fi].noalias() -= w * J_p.transpose() * r;
      eq.H_px[k].noalias() = w * J_p.transpose() * J_x;
    }
    gradient_max = 0.0;
    if (extra != nullptr) {
      H_extra.setZero();
      b_extra.setZero();
      extra->linearise(problem.poses, free_index, H_extra, b_extra);
      for (int f = 0; f < num_free; ++f) {
        eq.H_pp[static_cast<std::size_t>(f)] += H_extra.block<6, 6>(6 * f, 6 * f);
        eq.b_p[static_cast<std::size_t>(f)] += b_extra.segment<6>(6 * f);
        H_extra.block<6, 6>(6 * f, 6 * f).setZero();  // set into S with H_pp
      }
      if (extra_size > 0) {
        gradient_max = b_extra.tail(extra_size).cwiseAbs().maxCoeff();
        diag_extra = H_extra.diagonal().tail(extra_size).cwiseMax(kMinDiagonal).cwiseMin(kMaxDiagonal);
      }
    }
    for (std::size_t f = 0; f < eq.b_p.size(); ++f) {
      gradient_max = std::max(gradient_max, eq.b_p[f].cwiseAbs().maxCoeff());
      diag_p[f] = eq.H_pp[f].diagonal().cwiseMax(kMinDiagonal).cwiseMin(kMaxDiagonal);
    }
    for (std::size_t j = 0; j < num_points; ++j) {
      gradient_max = std::max(gradient_max, eq.b_x[j].cwiseAbs().maxCoeff());
      diag_x[j] = eq.H_xx[j].diagonal().cwiseMax(kMinDiagonal).cwiseMin(kMaxDiagonal);
    }
  };

  // Solves the damped system (H + diag / radius) step = b by eliminating the points; false when
  // the reduced system is not positive definite. Returns the model's predicted cost decrease.
  const auto solve_step = [&](double& model_decrease) {
    const double lambda = 1.0 / radius;
    if (extra != nullptr) {
      S = H_extra;
      S.diagonal().tail(extra_size) += lambda * diag_extra;
      rhs.tail(extra_size) = b_extra.tail(extra_size);
    } else {
      S.setZero();
    }
    for (int f = 0; f < num_free; ++f) {
      const std::size_t fi = static_cast<std::size_t>(f);
      S.block<6, 6>(6 * f, 6 * f) = eq.H_pp[fi];
      S.block<6, 6>(6 * f, 6 * f).diagonal() += lambda * diag_p[fi];
      rhs.segment<6>(6 * f) = eq.b_p[fi];
    }
    for (std::size_t j = 0; j < num_points; ++j) {
      Eigen::Matrix3d V = eq.H_xx[j];
      V.diagonal() += lambda * diag_x[j];
      V_inv[j] = V.inverse();
      for (std::size_t a = point_begin[j]; a < point_begin[j + 1]; ++a) {
        const BundleAdjustmentObservation& obs_a = problem.observations[order[a]];
        const int fa = free_index[static_cast<std::size_t>(obs_a.pose)];
        if (!obs_a.active || fa < 0) continue;
        const Matrix63 W_a = eq.H_px[order[a]] * V_inv[j];
        rhs.segment<6>(6 * fa).noalias() -= W_a * eq.b_x[j];
        for (std::size_t b = a; b < point_begin[j + 1]; ++b) {
          const BundleAdjustmentObservation& obs_b = problem.observations[order[b]];
          const int fb = free_index[static_cast<std::size_t>(obs_b.pose)];
          if (!obs_b.active || fb < 0) continue;
          const Matrix6d block = W_a * eq.H_px[order[b]].transpose();
          // Upper triangle only (LLT reads the lower one: write the transpose there).
          if (fa <= fb) {
            S.block<6, 6>(6 * fb, 6 * fa).noalias() -= block.transpose();
          } else {
            S.block<6, 6>(6 * fa, 6 * fb).noalias() -= block;
          }
        }
      }
    }
    if (reduced_size > 0) {
      llt.compute(S);  // reads the lower triangle
      if (llt.info() != Eigen::Success) return false;
      const Eigen::VectorXd dp = llt.solve(rhs);
      if (!dp.allFinite()) return false;
      for (int f = 0; f < num_free; ++f) step_p[static_cast<std::size_t>(f)] = dp.segment<6>(6 * f);
      if (extra_size > 0) step_extra = dp.tail(extra_size);
    }
    model_decrease = 0.0;
    if (extra_size > 0) {
      model_decrease += step_extra.dot(b_extra.tail(extra_size)) + lambda * step_extra.cwiseAbs2().dot(diag_extra);
    }
    for (int f = 0; f < num_free; ++f) {
      const std::size_t fi = static_cast<std::size_t>(f);
      model_decrease += step_p[fi].dot(eq.b_p[fi]) + lambda * step_p[fi].cwiseAbs2().dot(diag_p[fi]);
    }
    for (std::size_t j = 0; j < num_points; ++j) {
      Eigen::Vector3d b = eq.b_x[j];
      for (std::size_t a = point_begin[j]; a < point_begin[j + 1]; ++a) {
        const BundleAdjustmentObservation& obs = problem.observations[order[a]];
        const int f = free_index[static_cast<std::size_t>(obs.pose)];
        if (!obs.active || f < 0) continue;
        b.noalias() -= eq.H_px[order[a]].transpose() * step_p[static_cast<std::size_t>(f)];
      }
      step_x[j] = V_inv[j] * b;
      model_decrease += step_x[j].dot(eq.b_x[j]) + lambda * step_x[j].cwiseAbs2().dot(diag_x[j]);
    }
    model_decrease *= 0.5;
    return std::isfinite(model_decrease);
  };

  while (summary.iterations < options.max_iterations) {
    if (!linearised) {
      linearise();
      linearised = true;
      if (gradient_max <= options.gradient_tolerance) break;
    }
    ++summary.iterations;
    double model_decrease = 0.0;
    bool accepted = false;
    if (solve_step(model_decrease) && model_decrease > 0.0) {
      double step_norm2 = 0.0;
      double x_norm2 = 0.0;
      for (std::size_t i = 0; i < num_poses; ++i) {
        const int f = free_index[i];
        if (f < 0) continue;
        const Vector6d& d = step_p[static_cast<std::size_t>(f)];
        manifold.Plus(problem.poses[i].data(), d.data(), candidate_poses[i].data());
        step_norm2 += d.squaredNorm();
        for (double v : problem.poses[i]) x_norm2 += v * v;
      }
      for (std::size_t j = 0; j < num_points; ++j) {
        candidate_points[j] = problem.points[j] + step_x[j];
        step_norm2 += step_x[j].squaredNorm();
        x_norm2 += problem.points[j].squaredNorm();
      }
      double new_cost = total_cost(problem, candidate_poses, candidate_points);
      if (extra != nullptr) {
        new_cost += extra->cost(candidate_poses, &step_extra);
        step_norm2 += step_extra.squaredNorm();
        x_norm2 += extra->squared_norm();
      }
      const double actual_decrease = cost - new_cost;
      const double rho = actual_decrease / model_decrease;
      if (std::isfinite(new_cost) && rho > kMinRelativeDecrease) {
        accepted = true;
        ++summary.successful_steps;
        if (extra != nullptr) extra->update(step_extra);
        problem.poses.swap(candidate_poses);
        problem.points.swap(candidate_points);
        candidate_poses = problem.poses;
        candidate_points = problem.points;
        const double previous_cost = cost;
        cost = new_cost;
        linearised = false;
        radius = std::min(kMaxTrustRadius, radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)));
        decrease_factor = 2.0;
        const bool converged =
            std::abs(actual_decrease) <= options.function_tolerance * previous_cost ||
            std::sqrt(step_norm2) <= options.parameter_tolerance * (std::sqrt(x_norm2) + options.parameter_tolerance);
        if (options.stop_requested && options.stop_requested()) {
          summary.stopped = true;
          break;
        }
        if (converged) break;
        continue;
      }
    }
    if (!accepted) {
      radius /= decrease_factor;
      decrease_factor *= 2.0;
    }
    if (options.stop_requested && options.stop_requested()) {
      summary.stopped = true;
      break;
    }
    if (radius < kMinTrustRadius) break;
  }
  summary.final_cost = cost;
  return summary;
}

}  // namespace heslam

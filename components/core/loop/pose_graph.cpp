// SE(3) pose graph: Gauss-Newton / Levenberg-Marquardt with analytic Jacobians on the block-sparse
// normal equations, factorized by a supernodal block Cholesky (solve/block_sparse_cholesky.hpp) in a
// fill-reducing order of the keyframes.
// Until issue 41 this was a Ceres problem (autodiff, SPARSE_NORMAL_CHOLESKY): the same cost and the
// same convergence tests, 2-2.5x slower at 5,000 keyframes (its general sparse assembly and scalar
// ordering); tests/loop/pose_graph_test.cpp keeps that formulation as the reference it must match.
#include "components/core/loop/pose_graph.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/OrderingMethods>

#include "components/core/imu/so3.hpp"
#include "components/core/solve/block_sparse_cholesky.hpp"

namespace heslam {
namespace {

// One edge between unknowns (index -1: a fixed vertex).
struct SolverEdge {
  int from_vertex = 0;  // into the vertex arrays
  int to_vertex = 0;
  int from_unknown = -1;
  int to_unknown = -1;
  Eigen::Matrix3d R_measured_transpose;
  Eigen::Vector3d t_measured;
  double sqrt_weight = 1.0;
  // Offsets into H's value array of the first entry of each of a block's 6 columns: (from, from),
  // (to, to), (upper of from/to).
  std::array<int, 6> offset_ff{}, offset_tt{}, offset_ft{};
};

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Residual (translation, rotation) and its Jacobians with respect to the right perturbations
// (phi, dt) of each end: R <- R Exp(phi), t <- t + dt. Rotation residual 2 vec(q(R_m^T R_f^T R_t)):
// Ceres's formulation above, so both solvers minimise the same cost.
Vector6d edge_residual(const SolverEdge& e, const Eigen::Matrix3d& R_f, const Eigen::Vector3d& t_f,
                       const Eigen::Matrix3d& R_t, const Eigen::Vector3d& t_t, Matrix6d* J_f, Matrix6d* J_t) {
  const Eigen::Vector3d d = R_f.transpose() * (t_t - t_f);
  const Eigen::Matrix3d M = R_f.transpose() * R_t;
  const Eigen::Quaterniond q_error(e.R_measured_transpose * M);
  Vector6d r;
  r.head<3>() = e.sqrt_weight * (d - e.t_measured);
  r.tail<3>() = 2.0 * e.sqrt_weight * q_error.vec();
  if (J_f != nullptr) {
    const Eigen::Matrix3d dq = e.sqrt_weight * (q_error.w() * Eigen::Matrix3d::Identity() + so3::hat(q_error.vec()));
    // Columns: (phi, dt). Rows: (translation, rotation).
    J_f->setZero();
    J_t->setZero();
    J_f->block<3, 3>(0, 0) = e.sqrt_weight * so3::hat(d);
    J_f->block<3, 3>(0, 3) = -e.sqrt_weight * R_f.transpose();
    J_f->block<3, 3>(3, 0) = -dq * M.transpose();
    J_t->block<3, 3>(0, 3) = e.sqrt_weight * R_f.transpose();
    J_t->block<3, 3>(3, 0) = dq;
  }
  return r;
}

// Huber on the squared norm, as Ceres's HuberLoss: rho(s) and its IRLS weight rho'(s).
double robust_cost(double squared_norm, const PoseGraphOptions& options) {
  if (!options.robust || squared_norm <= options.huber_delta * options.huber_delta) return squared_norm;
  return 2.0 * options.huber_delta * std::sqrt(squared_norm) - options.huber_delta * options.huber_delta;
}
double robust_weight(double squared_norm, const PoseGraphOptions& options) {
  if (!options.robust || squared_norm <= options.huber_delta * options.huber_delta) return 1.0;
  return options.huber_delta / std::sqrt(squared_norm);
}

// Gauss-Newton with Levenberg-Marquardt damping on the block-sparse normal equations, the pattern
// and its fill-reducing ordering analysed once (AMD on the keyframe graph), factorized by dense panels
// (BlockSparseCholesky). A loop closing a long chain of keyframes is what costs: its ring has twice the
// chain's band in any order, and at 5,000 keyframes L grows from 2.7 M to 5.0 M entries and 3.5x the
// flops; Eigen's scalar simplicial LL^T took 85 % of LoopCorrectionBuilder::compute there (1.9 of 2.25 s
// of CPU), the panels a quarter of that (docs/loop_closing.md, "Measured"). Not CHOLMOD's
// supernodal method: it runs its copies in 4 OpenMP threads whatever the machine, and was slower
// than the simplicial one on the chain alone (1.5-1.9 s of CPU against 1.0-1.7 s, issue 41).
// D = 6: SE(3) unknowns (phi, dt), R <- R Exp(phi). D = 4 (inertial, options.four_dof): (psi, dt), a yaw
// psi about the world's gravity axis a, R <- Exp(psi a) R = R Exp(psi R^T a), so the 6-DoF Jacobians
// times [R^T a, 0; 0, I3] are the 4-DoF ones, and the direction of gravity in every camera (roll and
// pitch) never changes.
template <int D>
class GaussNewtonPoseGraph {
 public:
  GaussNewtonPoseGraph(std::vector<Eigen::Matrix3d> R, std::vector<Eigen::Vector3d> t, std::vector<int> unknown_of,
                       int unknowns, std::vector<SolverEdge> edges, const PoseGraphOptions& options,
                       const Eigen::Vector3d& yaw_axis_w)
      : R_(std::move(R)),
        t_(std::move(t)),
        unknown_of_(std::move(unknown_of)),
        unknowns_(unknowns),
        edges_(std::move(edges)),
        options_(options),
        yaw_axis_w_(yaw_axis_w) {
    build_pattern();
  }

  // Runs the minimisation; fills the stats' costs and iterations.
  void solve(PoseGraphStats& stats) {
    double cost = total_cost(R_, t_);
    stats.initial_cost = cost;
    double lambda = kInitialLambda;
    // The unknowns are already in a fill-reducing order (compute_gauss_newton).
    BlockSparseCholesky solver;
    solver.analyze(H_, D);
    Eigen::VectorXd gradient(D * unknowns_);
    int iterations = 0;
    while (iterations < options_.max_iterations) {
      linearize(gradient);
      if (gradient.lpNorm<Eigen::Infinity>() <= kGradientTolerance) break;
      bool accepted = false;
      while (!accepted && iterations < options_.max_iterations) {
        ++iterations;
        if (!factorize(solver, lambda)) {
          lambda *= kLambdaUp;
          continue;
        }
        const Eigen::VectorXd step = solver.solve(-gradient);
        std::vector<Eigen::Matrix3d> R = R_;
        std::vector<Eigen::Vector3d> t = t_;
        for (std::size_t v = 0; v < R.size(); ++v) {
          const int u = unknown_of_[v];
          if (u < 0) continue;
          if constexpr (D == 6) {
            R[v] = R[v] * so3::exp(step.segment<3>(6 * u));
          } else {
            R[v] = so3::exp(step[D * u] * yaw_axis_w_) * R[v];
          }
          t[v] += step.segment<3>(D * u + D - 3);
        }
        const double new_cost = total_cost(R, t);
        if (new_cost < cost) {
          accepted = true;
          R_ = std::move(R);
          t_ = std::move(t);
          const double change = cost - new_cost;
          cost = new_cost;
          lambda = std::max(lambda / kLambdaDown, kMinLambda);
          if (change <= kFunctionTolerance * (cost + change)) {
            stats.final_cost = cost;
            stats.iterations = iterations;
            return;
          }
        } else {
          lambda *= kLambdaUp;
          if (step.norm() <= kStepTolerance) {
            stats.final_cost = cost;
            stats.iterations = iterations;
            return;
          }
        }
      }
    }
    stats.final_cost = cost;
    stats.iterations = iterations;
  }

  // Factorizes H + lambda diag(H) (H itself is left undamped). False when it is not positive definite.
  bool factorize(BlockSparseCholesky& solver, double lambda) {
    const Eigen::VectorXd diagonal = H_.diagonal();
    for (int k = 0; k < H_.outerSize(); ++k) {
      H_.coeffRef(k, k) = diagonal[k] + lambda * std::max(diagonal[k], kMinDiagonal);
    }
    const bool factorized = solver.factorize(H_);
    for (int k = 0; k < H_.outerSize(); ++k) H_.coeffRef(k, k) = diagonal[k];
    return factorized;
  }

  const std::vector<Eigen::Matrix3d>& R() const { return R_; }
  const std::vector<Eigen::Vector3d>& t() const { return t_; }

 private:
  // Ceres's defaults: relative cost change and step size at which the minimisation has converged.
  static constexpr double kFunctionTolerance = 1e-6;
  static constexpr double kGradientTolerance = 1e-10;
  static constexpr double kStepTolerance = 1e-8;
  // LM damping relative to H's diagonal: 1e-12, a Gauss-Newton step unless a step fails. It must stay
  // below the curvature of the graph's softest directions relative to the diagonal (a loop bending as
  // a whole; about 1 / N^2 for a chain of N keyframes): with Ceres's 1e-8 each step covered only part
  // of the bend, and at 5,000 keyframes it took 9 iterations instead of 4 (the last 5 moving poses by
  // metres for a relative cost change of 1e-1 .. 1e-5), to the same optimum.
  static constexpr double kInitialLambda = 1e-12;
  static constexpr double kMinLambda = 1e-16;
  static constexpr double kLambdaUp = 10.0;
  static constexpr double kLambdaDown = 3.0;
  static constexpr double kMinDiagonal = 1e-6;

  using VectorDd = Eigen::Matrix<double, D, 1>;
  using MatrixDd = Eigen::Matrix<double, D, D>;
  using Matrix6Dd = Eigen::Matrix<double, 6, D>;

  // The Jacobian with respect to this solver's unknowns of a vertex with rotation R.
  Matrix6Dd reduce(const Matrix6d& J, const Eigen::Matrix3d& R) const {
    if constexpr (D == 6) {
      return J;
    } else {
      Matrix6Dd reduced;
      reduced.col(0) = J.leftCols<3>() * (R.transpose() * yaw_axis_w_);
      reduced.template rightCols<3>() = J.rightCols<3>();
      return reduced;
    }
  }

  double total_cost(const std::vector<Eigen::Matrix3d>& R, const std::vector<Eigen::Vector3d>& t) const {
    double cost = 0.0;
    for (const SolverEdge& e : edges_) {
      const Vector6d r =
          edge_residual(e, R[e.from_vertex], t[e.from_vertex], R[e.to_vertex], t[e.to_vertex], nullptr, nullptr);
      cost += robust_cost(r.squaredNorm(), options_);
    }
    return 0.5 * cost;
  }

  // H (lower blocks) and the gradient J^T r at the current poses.
  void linearize(Eigen::VectorXd& gradient) {
    std::fill(H_.valuePtr(), H_.valuePtr() + H_.nonZeros(), 0.0);
    gradient.setZero();
    Matrix6d J_f6, J_t6;
    for (const SolverEdge& e : edges_) {
      const Vector6d r =
          edge_residual(e, R_[e.from_vertex], t_[e.from_vertex], R_[e.to_vertex], t_[e.to_vertex], &J_f6, &J_t6);
      const Matrix6Dd J_f = reduce(J_f6, R_[e.from_vertex]);
      const Matrix6Dd J_t = reduce(J_t6, R_[e.to_vertex]);
      const double w = robust_weight(r.squaredNorm(), options_);
      if (e.from_unknown >= 0) {
        add_block(e.offset_ff, w * J_f.transpose() * J_f);
        gradient.template segment<D>(D * e.from_unknown) += w * J_f.transpose() * r;
      }
      if (e.to_unknown >= 0) {
        add_block(e.offset_tt, w * J_t.transpose() * J_t);
        gradient.template segment<D>(D * e.to_unknown) += w * J_t.transpose() * r;
      }
      if (e.from_unknown >= 0 && e.to_unknown >= 0) {
        // The stored block is (larger unknown, smaller unknown).
        if (e.from_unknown < e.to_unknown) {
          add_block(e.offset_ft, w * J_t.transpose() * J_f);
        } else {
          add_block(e.offset_ft, w * J_f.transpose() * J_t);
        }
      }
    }
  }

  void add_block(const std::array<int, 6>& column_offsets, const MatrixDd& block) {
    double* values = H_.valuePtr();
    for (int c = 0; c < D; ++c) {
      for (int r = 0; r < D; ++r) values[column_offsets[c] + r] += block(r, c);
    }
  }

  // The block pattern: a DxD block per unknown on the diagonal and per edge between two unknowns.
  void build_pattern() {
    std::vector<std::vector<int>> rows_of_column(unknowns_);  // block rows of each block column (lower)
    for (int u = 0; u < unknowns_; ++u) rows_of_column[u].push_back(u);
    for (const SolverEdge& e : edges_) {
      if (e.from_unknown < 0 || e.to_unknown < 0) continue;
      const int row = std::max(e.from_unknown, e.to_unknown), column = std::min(e.from_unknown, e.to_unknown);
      rows_of_column[column].push_back(row);
    }
    for (auto& rows : rows_of_column) {
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    }
    const int n = D * unknowns_;
    std::vector<int> outer(n + 1, 0);
    for (int column = 0; column < unknowns_; ++column) {
      for (int c = 0; c < D; ++c) outer[D * column + c + 1] = outer[D * column + c] + D * rows_of_column[column].size();
    }
    H_.resize(n, n);
    H_.resizeNonZeros(outer[n]);
    std::copy(outer.begin(), outer.end(), H_.outerIndexPtr());
    for (int column = 0; column < unknowns_; ++column) {
      for (int c = 0; c < D; ++c) {
        int* inner = H_.innerIndexPtr() + outer[D * column + c];
        for (const int row : rows_of_column[column]) {
          for (int r = 0; r < D; ++r) *inner++ = D * row + r;
        }
      }
    }
    const auto offsets = [&](int row, int column) {
      const auto& rows = rows_of_column[column];
      const int k = static_cast<int>(std::lower_bound(rows.begin(), rows.end(), row) - rows.begin());
      std::array<int, 6> result{};
      for (int c = 0; c < D; ++c) result[c] = outer[D * column + c] + D * k;
      return result;
    };
    for (SolverEdge& e : edges_) {
      if (e.from_unknown >= 0) e.offset_ff = offsets(e.from_unknown, e.from_unknown);
      if (e.to_unknown >= 0) e.offset_tt = offsets(e.to_unknown, e.to_unknown);
      if (e.from_unknown >= 0 && e.to_unknown >= 0) {
        e.offset_ft = offsets(std::max(e.from_unknown, e.to_unknown), std::min(e.from_unknown, e.to_unknown));
      }
    }
  }

  std::vector<Eigen::Matrix3d> R_;
  std::vector<Eigen::Vector3d> t_;
  std::vector<int> unknown_of_;  // per vertex: its unknown's index, -1 when fixed
  int unknowns_;
  std::vector<SolverEdge> edges_;
  PoseGraphOptions options_;
  Eigen::Vector3d yaw_axis_w_;     // unit, along gravity (D = 4)
  Eigen::SparseMatrix<double> H_;  // lower triangle
};

void compute_gauss_newton(const std::map<KeyframeId, Pose3>& initial_T_wc, const std::vector<PoseGraphEdge>& edges,
                          const std::set<KeyframeId>& fixed, const PoseGraphOptions& options, PoseGraphResult& result) {
  std::map<KeyframeId, int> vertex_of;
  std::vector<KeyframeId> ids;
  std::vector<Eigen::Matrix3d> R;
  std::vector<Eigen::Vector3d> t;
  for (const auto& [id, T_wc] : initial_T_wc) {
    vertex_of[id] = static_cast<int>(ids.size());
    ids.push_back(id);
    R.push_back(T_wc.rotation());
    t.push_back(T_wc.translation());
  }
  std::vector<SolverEdge> solver_edges;
  std::vector<bool> touched(ids.size(), false);
  for (const PoseGraphEdge& edge : edges) {
    const auto from = vertex_of.find(edge.from);
    const auto to = vertex_of.find(edge.to);
    if (from == vertex_of.end() || to == vertex_of.end() || edge.from == edge.to) {
      ++result.stats.skipped_edges;
      continue;
    }
    SolverEdge e;
    e.from_vertex = from->second;
    e.to_vertex = to->second;
    e.R_measured_transpose = edge.T_from_to.rotation().transpose();
    e.t_measured = edge.T_from_to.translation();
    e.sqrt_weight = std::sqrt(edge.weight);
    solver_edges.push_back(e);
    touched[e.from_vertex] = touched[e.to_vertex] = true;
    ++result.stats.edges;
  }
  std::vector<int> unknown_of(ids.size(), -1);
  int unknowns = 0;
  for (std::size_t v = 0; v < ids.size(); ++v) {
    if (!touched[v]) continue;
    ++result.stats.vertices;
    if (fixed.count(ids[v]) != 0) {
      ++result.stats.fixed_vertices;
    } else {
      unknown_of[v] = unknowns++;
    }
  }
  if (result.stats.edges == 0 || unknowns == 0) return;
  // A fill-reducing order of the unknowns, found on the pose graph itself (one node per keyframe, 36
  // times smaller than the scalar system): minimum degree (AMD).
  {
    std::vector<Eigen::Triplet<double>> links;
    for (int u = 0; u < unknowns; ++u) links.emplace_back(u, u, 1.0);
    for (const SolverEdge& e : solver_edges) {
      const int a = unknown_of[e.from_vertex], b = unknown_of[e.to_vertex];
      if (a < 0 || b < 0) continue;
      links.emplace_back(a, b, 1.0);
      links.emplace_back(b, a, 1.0);
    }
    Eigen::SparseMatrix<double> adjacency(unknowns, unknowns);
    adjacency.setFromTriplets(links.begin(), links.end());
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> new_to_old;
    Eigen::AMDOrdering<int>()(adjacency, new_to_old);
    const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> old_to_new = new_to_old.inverse();
    for (int& u : unknown_of) {
      if (u >= 0) u = old_to_new.indices()[u];
    }
  }
  for (SolverEdge& e : solver_edges) {
    e.from_unknown = unknown_of[e.from_vertex];
    e.to_unknown = unknown_of[e.to_vertex];
  }
  const auto solve_and_store = [&](auto& solver) {
    solver.solve(result.stats);
    for (std::size_t v = 0; v < ids.size(); ++v) {
      if (unknown_of[v] < 0) continue;
      Pose3 T_wc = Pose3::Identity();
      T_wc.linear() = Eigen::Quaterniond(solver.R()[v]).normalized().toRotationMatrix();
      T_wc.translation() = solver.t()[v];
      result.T_wc[ids[v]] = T_wc;
    }
  };
  if (options.four_dof) {
    GaussNewtonPoseGraph<4> solver(std::move(R), std::move(t), unknown_of, unknowns, std::move(solver_edges), options,
                                   options.gravity_w.normalized());
    solve_and_store(solver);
  } else {
    GaussNewtonPoseGraph<6> solver(std::move(R), std::move(t), unknown_of, unknowns, std::move(solver_edges), options,
                                   Eigen::Vector3d::Zero());
    solve_and_store(solver);
  }
}

}  // namespace

Eigen::Matrix3d yaw_about_gravity(const Eigen::Matrix3d& R, const Eigen::Vector3d& gravity_w) {
  const Eigen::Vector3d axis = gravity_w.normalized();
  const Eigen::Quaterniond q(R);
  const double along = q.vec().dot(axis);
  const double norm = std::hypot(q.w(), along);
  if (!(norm > 0.0)) return Eigen::Matrix3d::Identity();  // a half turn about a horizontal axis: no yaw part
  return Eigen::Quaterniond(q.w() / norm, along * axis.x() / norm, along * axis.y() / norm, along * axis.z() / norm)
      .toRotationMatrix();
}

PoseGraphResult PoseGraph::compute(const std::map<KeyframeId, Pose3>& initial_T_wc,
                                   const std::vector<PoseGraphEdge>& edges, const std::set<KeyframeId>& fixed) const {
  if (options_.four_dof && (!options_.gravity_w.allFinite() || !(options_.gravity_w.norm() > 0.0))) {
    throw std::invalid_argument(
        "PoseGraph: gravity_w: expected a finite non-zero direction for the 4-DoF graph, got (" +
        std::to_string(options_.gravity_w.x()) + ", " + std::to_string(options_.gravity_w.y()) + ", " +
        std::to_string(options_.gravity_w.z()) + ")");
  }
  const auto start = std::chrono::steady_clock::now();
  PoseGraphResult result;
  result.T_wc = initial_T_wc;
  compute_gauss_newton(initial_T_wc, edges, fixed, options_, result);
  result.stats.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace heslam

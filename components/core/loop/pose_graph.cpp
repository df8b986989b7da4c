// SE(3) pose graph: autodiff relative-pose residuals on quaternion + translation vertices.
#include "components/core/loop/pose_graph.hpp"

#include <chrono>
#include <cmath>

#include <ceres/ceres.h>

namespace heslam {
namespace {

// ORB-SLAM2 starts LM with lambda 1e-16, i.e. almost a Gauss-Newton step; a trust region this large
// does the same while staying finite for a weakly constrained direction.
constexpr double kInitialTrustRegionRadius = 1e8;

// Camera-to-world pose of one vertex: quaternion (x, y, z, w, Eigen's storage order) and translation.
struct VertexBlock {
  double q_wc[4];
  double t_wc[3];
};

VertexBlock to_block(const Pose3& T_wc) {
  const Eigen::Quaterniond q(T_wc.rotation());
  return {{q.x(), q.y(), q.z(), q.w()}, {T_wc.translation().x(), T_wc.translation().y(), T_wc.translation().z()}};
}

Pose3 from_block(const VertexBlock& block) {
  Pose3 T_wc = Pose3::Identity();
  T_wc.linear() =
      Eigen::Quaterniond(block.q_wc[3], block.q_wc[0], block.q_wc[1], block.q_wc[2]).normalized().toRotationMatrix();
  T_wc.translation() = Eigen::Vector3d(block.t_wc[0], block.t_wc[1], block.t_wc[2]);
  return T_wc;
}

class RelativePoseResidual {
 public:
  RelativePoseResidual(const Pose3& T_from_to, double weight)
      : q_measured_inverse_(Eigen::Quaterniond(T_from_to.rotation()).conjugate()),
        t_measured_(T_from_to.translation()),
        sqrt_weight_(std::sqrt(weight)) {}

  template <typename T>
  bool operator()(const T* q_from, const T* t_from, const T* q_to, const T* t_to, T* residuals) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_wf(q_from);
    const Eigen::Map<const Eigen::Quaternion<T>> q_wt(q_to);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_wf(t_from);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_wt(t_to);
    const Eigen::Quaternion<T> q_wf_inverse = q_wf.conjugate();
    const Eigen::Quaternion<T> q_ft = q_wf_inverse * q_wt;
    const Eigen::Matrix<T, 3, 1> t_ft = q_wf_inverse * (t_wt - t_wf);
    const Eigen::Quaternion<T> q_error = q_measured_inverse_.template cast<T>() * q_ft;
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residuals);
    r.template head<3>() = T(sqrt_weight_) * (t_ft - t_measured_.template cast<T>());
    r.template tail<3>() = T(2.0 * sqrt_weight_) * q_error.vec();
    return true;
  }

 private:
  Eigen::Quaterniond q_measured_inverse_;
  Eigen::Vector3d t_measured_;
  double sqrt_weight_;
};

}  // namespace

PoseGraphResult PoseGraph::compute(const std::map<KeyframeId, Pose3>& initial_T_wc,
                                   const std::vector<PoseGraphEdge>& edges, const std::set<KeyframeId>& fixed) const {
  const auto start = std::chrono::steady_clock::now();
  PoseGraphResult result;
  result.T_wc = initial_T_wc;

  // Contiguous storage in id order: Ceres orders blocks by address, so this keeps runs reproducible.
  std::vector<VertexBlock> blocks;
  std::map<KeyframeId, std::size_t> index_of;
  for (const auto& [id, T_wc] : initial_T_wc) {
    index_of[id] = blocks.size();
    blocks.push_back(to_block(T_wc));
  }

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;  // one manifold shared by all vertices
  ceres::Problem problem(problem_options);
  ceres::EigenQuaternionManifold quaternion_manifold;
  for (const PoseGraphEdge& edge : edges) {
    const auto from = index_of.find(edge.from);
    const auto to = index_of.find(edge.to);
    if (from == index_of.end() || to == index_of.end() || edge.from == edge.to) {
      ++result.stats.skipped_edges;
      continue;
    }
    VertexBlock& a = blocks[from->second];
    VertexBlock& b = blocks[to->second];
    // Ceres owns cost and loss (the problem's default ownership).
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseResidual, 6, 4, 3, 4, 3>(
        new RelativePoseResidual(edge.T_from_to, edge.weight));
    ceres::LossFunction* loss = options_.robust ? new ceres::HuberLoss(options_.huber_delta) : nullptr;
    problem.AddResidualBlock(cost, loss, a.q_wc, a.t_wc, b.q_wc, b.t_wc);
    ++result.stats.edges;
  }
  for (const auto& [id, index] : index_of) {
    VertexBlock& block = blocks[index];
    if (!problem.HasParameterBlock(block.q_wc)) continue;
    ++result.stats.vertices;
    problem.SetManifold(block.q_wc, &quaternion_manifold);
    if (fixed.count(id) != 0) {
      problem.SetParameterBlockConstant(block.q_wc);
      problem.SetParameterBlockConstant(block.t_wc);
      ++result.stats.fixed_vertices;
    }
  }

  if (result.stats.edges > 0) {
    ceres::Solver::Options solver_options;
    solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver_options.max_num_iterations = options_.max_iterations;
    solver_options.initial_trust_region_radius = kInitialTrustRegionRadius;
    solver_options.num_threads = 1;
    solver_options.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    result.stats.initial_cost = summary.initial_cost;
    result.stats.final_cost = summary.final_cost;
    result.stats.iterations = static_cast<int>(summary.iterations.size()) - 1;  // entry 0 is the start
    for (const auto& [id, index] : index_of) {
      const bool moved = fixed.count(id) == 0 && problem.HasParameterBlock(blocks[index].q_wc);
      if (moved) result.T_wc[id] = from_block(blocks[index]);
    }
  }
  result.stats.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace heslam

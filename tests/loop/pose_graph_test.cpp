// SE(3) pose graph on a circular trajectory with accumulated odometry drift and one loop edge.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>

#include <ceres/ceres.h>

#include "components/core/loop/pose_graph.hpp"

namespace heslam {
namespace {

constexpr int kVertices = 60;
constexpr double kRadiusM = 5.0;

Pose3 true_pose(int k) {
  const double theta = 2.0 * M_PI * k / kVertices;
  Pose3 T_wc = Pose3::Identity();
  T_wc.linear() = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T_wc.translation() =
      Eigen::Vector3d(kRadiusM * std::sin(theta), 0.2 * std::sin(2 * theta), kRadiusM * std::cos(theta));
  return T_wc;
}

KeyframeId id_of(int k) { return static_cast<KeyframeId>(k + 1); }

struct DriftedGraph {
  std::map<KeyframeId, Pose3> initial_T_wc;
  std::vector<PoseGraphEdge> edges;
};

// Odometry edges biased by 0.4 deg yaw, 0.1 deg roll and 1 cm per step, the initial guess chained
// from them; the loop edge (last -> first) is exact.
DriftedGraph make_graph() {
  DriftedGraph graph;
  Pose3 bias = Pose3::Identity();
  bias.linear() =
      (Eigen::AngleAxisd(0.007, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(0.0017, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  bias.translation() = Eigen::Vector3d(0.01, 0.0, 0.005);
  graph.initial_T_wc[id_of(0)] = true_pose(0);
  for (int k = 1; k < kVertices; ++k) {
    const Pose3 measured = true_pose(k - 1).inverse() * true_pose(k) * bias;
    graph.edges.push_back({id_of(k - 1), id_of(k), measured, 1.0});
    graph.initial_T_wc[id_of(k)] = graph.initial_T_wc[id_of(k - 1)] * measured;
  }
  graph.edges.push_back({id_of(kVertices - 1), id_of(0), true_pose(kVertices - 1).inverse() * true_pose(0), 1.0});
  return graph;
}

// The pose graph as it was solved until issue 41: a Ceres problem (quaternion manifold + translation
// per vertex, autodiff residuals, SPARSE_NORMAL_CHOLESKY, Ceres's convergence tests). PoseGraph must
// reach the same optimum.
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

class CeresRelativePoseResidual {
 public:
  CeresRelativePoseResidual(const Pose3& T_from_to, double weight)
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

PoseGraphResult ceres_reference(const std::map<KeyframeId, Pose3>& initial_T_wc,
                                const std::vector<PoseGraphEdge>& edges, const std::set<KeyframeId>& fixed,
                                const PoseGraphOptions& options = {}, double function_tolerance = 1e-6) {
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
    auto* cost = new ceres::AutoDiffCostFunction<CeresRelativePoseResidual, 6, 4, 3, 4, 3>(
        new CeresRelativePoseResidual(edge.T_from_to, edge.weight));
    ceres::LossFunction* loss = options.robust ? new ceres::HuberLoss(options.huber_delta) : nullptr;
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
    solver_options.max_num_iterations = function_tolerance < 1e-6 ? 100 : options.max_iterations;
    solver_options.function_tolerance = function_tolerance;
    solver_options.gradient_tolerance = function_tolerance < 1e-6 ? 1e-16 : 1e-10;
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
  return result;
}

// Largest position (m) and rotation (rad) difference between two solutions' common poses.
std::pair<double, double> largest_difference(const PoseGraphResult& a, const PoseGraphResult& b) {
  double position_m = 0.0, rotation_rad = 0.0;
  for (const auto& [id, T_wc] : a.T_wc) {
    const Pose3& other = b.T_wc.at(id);
    position_m = std::max(position_m, (T_wc.translation() - other.translation()).norm());
    rotation_rad = std::max(rotation_rad, Eigen::AngleAxisd(T_wc.rotation().transpose() * other.rotation()).angle());
  }
  return {position_m, rotation_rad};
}

double max_position_error_m(const std::map<KeyframeId, Pose3>& T_wc) {
  double largest = 0.0;
  for (int k = 0; k < kVertices; ++k) {
    largest = std::max(largest, (T_wc.at(id_of(k)).translation() - true_pose(k).translation()).norm());
  }
  return largest;
}

TEST(LoopPoseGraph, LoopEdgeRemovesAccumulatedDrift) {
  const DriftedGraph graph = make_graph();
  const KeyframeId last = id_of(kVertices - 1);
  const Eigen::Vector3d true_end = true_pose(kVertices - 1).translation();
  const double initial_end_error_m = (graph.initial_T_wc.at(last).translation() - true_end).norm();
  ASSERT_GT(initial_end_error_m, 1.0);

  const PoseGraphResult result = PoseGraph().compute(graph.initial_T_wc, graph.edges, {id_of(0)});
  const double final_end_error_m = (result.T_wc.at(last).translation() - true_end).norm();
  EXPECT_LT(final_end_error_m * 10.0, initial_end_error_m);
  EXPECT_LT(max_position_error_m(result.T_wc), 0.5 * max_position_error_m(graph.initial_T_wc));
  EXPECT_EQ(result.T_wc.at(id_of(0)).matrix(), graph.initial_T_wc.at(id_of(0)).matrix());
  EXPECT_LT(result.stats.final_cost, result.stats.initial_cost);
  EXPECT_EQ(result.stats.vertices, kVertices);
  EXPECT_EQ(result.stats.fixed_vertices, 1);
  EXPECT_EQ(result.stats.edges, kVertices);
  EXPECT_LE(result.stats.iterations, 20);
}

TEST(LoopPoseGraph, FixedVerticesStayBitIdenticalAndRunsRepeat) {
  const DriftedGraph graph = make_graph();
  const std::set<KeyframeId> fixed{id_of(0), id_of(30)};
  const PoseGraphResult first = PoseGraph().compute(graph.initial_T_wc, graph.edges, fixed);
  const PoseGraphResult second = PoseGraph().compute(graph.initial_T_wc, graph.edges, fixed);
  for (const KeyframeId id : fixed) EXPECT_EQ(first.T_wc.at(id).matrix(), graph.initial_T_wc.at(id).matrix());
  for (const auto& [id, T_wc] : first.T_wc) EXPECT_EQ(T_wc.matrix(), second.T_wc.at(id).matrix());
}

TEST(LoopPoseGraph, ReachesTheOptimumOfTheCeresFormulation) {
  // Both solvers stop at the same relative cost change (1e-6), each a little short of the optimum:
  // ours must be at least as close to it (the Ceres problem run to 1e-14) as Ceres with its defaults.
  const DriftedGraph graph = make_graph();
  for (const std::set<KeyframeId>& fixed :
       {std::set<KeyframeId>{id_of(0)}, std::set<KeyframeId>{id_of(0), id_of(30)}}) {
    SCOPED_TRACE(std::to_string(fixed.size()) + " fixed");
    const PoseGraphResult ours = PoseGraph().compute(graph.initial_T_wc, graph.edges, fixed);
    const PoseGraphResult ceres = ceres_reference(graph.initial_T_wc, graph.edges, fixed);
    const PoseGraphResult optimum = ceres_reference(graph.initial_T_wc, graph.edges, fixed, {}, 1e-14);
    EXPECT_NEAR(ours.stats.initial_cost, ceres.stats.initial_cost, 1e-9 * ceres.stats.initial_cost);
    EXPECT_LE(ours.stats.final_cost - optimum.stats.final_cost,
              1e-9 + 1.01 * (ceres.stats.final_cost - optimum.stats.final_cost));
    const auto [ours_position_m, ours_rotation_rad] = largest_difference(ours, optimum);
    const auto [ceres_position_m, ceres_rotation_rad] = largest_difference(ceres, optimum);
    std::printf("from the optimum: ours %.3g m %.3g rad, Ceres %.3g m %.3g rad\n", ours_position_m, ours_rotation_rad,
                ceres_position_m, ceres_rotation_rad);
    EXPECT_LT(ours_position_m, std::max(1e-7, 1.5 * ceres_position_m));
    EXPECT_LT(ours_rotation_rad, std::max(1e-8, 1.5 * ceres_rotation_rad));
    EXPECT_EQ(ours.stats.vertices, ceres.stats.vertices);
    EXPECT_EQ(ours.stats.edges, ceres.stats.edges);
  }
}

TEST(LoopPoseGraph, RobustKernelReachesTheCeresOptimumWithAWrongEdge) {
  DriftedGraph graph = make_graph();
  // A wrong loop edge half a metre off: Huber keeps it from pulling the whole circle.
  Pose3 wrong = true_pose(20).inverse() * true_pose(50);
  wrong.translation() += Eigen::Vector3d(0.5, 0.0, 0.0);
  graph.edges.push_back({id_of(20), id_of(50), wrong, 1.0});
  PoseGraphOptions options;
  options.robust = true;
  const PoseGraphResult ours = PoseGraph(options).compute(graph.initial_T_wc, graph.edges, {id_of(0)});
  const PoseGraphResult reference = ceres_reference(graph.initial_T_wc, graph.edges, {id_of(0)}, options);
  const auto [position_m, rotation_rad] = largest_difference(ours, reference);
  EXPECT_LT(position_m, 1e-4);
  EXPECT_LT(rotation_rad, 1e-5);
  EXPECT_NEAR(ours.stats.final_cost, reference.stats.final_cost, 1e-3 * reference.stats.final_cost);
}

TEST(LoopPoseGraph, UnknownVerticesAreSkippedAndIsolatedOnesKept) {
  std::map<KeyframeId, Pose3> T_wc{{1, true_pose(0)}, {2, true_pose(1)}, {3, true_pose(2)}};
  const std::vector<PoseGraphEdge> edges{{1, 2, true_pose(0).inverse() * true_pose(1), 1.0},
                                         {2, 99, Pose3::Identity(), 1.0}};
  const PoseGraphResult result = PoseGraph().compute(T_wc, edges, {1});
  EXPECT_EQ(result.stats.skipped_edges, 1);
  EXPECT_EQ(result.stats.edges, 1);
  EXPECT_EQ(result.T_wc.at(3).matrix(), T_wc.at(3).matrix());
  EXPECT_LT((result.T_wc.at(2).translation() - true_pose(1).translation()).norm(), 1e-9);
}

// 4-DoF (inertial) graphs. Gravity along a tilted axis of the world: the variant must not assume a
// gravity-aligned (z up) world.
const Eigen::Vector3d kGravityDirectionW = Eigen::Vector3d(0.3, -1.0, 0.2).normalized();

// The circle of true_pose with roll and pitch varying along it.
Pose3 inertial_true_pose(int k) {
  const double theta = 2.0 * M_PI * k / kVertices;
  Pose3 T_wc = true_pose(k);
  T_wc.linear() = T_wc.rotation() * Eigen::AngleAxisd(0.1 * std::sin(3 * theta), Eigen::Vector3d::UnitX()) *
                  Eigen::AngleAxisd(0.05 * std::cos(theta), Eigen::Vector3d::UnitZ());
  return T_wc;
}

// Gravity's direction in each camera: what roll and pitch are (yaw about gravity leaves it alone).
std::map<KeyframeId, Eigen::Vector3d> gravity_in_cameras(const std::map<KeyframeId, Pose3>& T_wc) {
  std::map<KeyframeId, Eigen::Vector3d> result;
  for (const auto& [id, pose] : T_wc) result[id] = pose.rotation().transpose() * kGravityDirectionW;
  return result;
}

double largest_gravity_change(const std::map<KeyframeId, Pose3>& a, const std::map<KeyframeId, Pose3>& b) {
  const auto gravity_a = gravity_in_cameras(a), gravity_b = gravity_in_cameras(b);
  double largest = 0.0;
  for (const auto& [id, g] : gravity_a) largest = std::max(largest, (g - gravity_b.at(id)).norm());
  return largest;
}

PoseGraphOptions four_dof_options() {
  PoseGraphOptions options;
  options.four_dof = true;
  options.gravity_w = 9.81 * kGravityDirectionW;  // any length
  return options;
}

TEST(LoopPoseGraph, FourDofRemovesYawAndTranslationDriftExactlyAndKeepsRollAndPitch) {
  // Exact edges (odometry and the loop); the initial guess drifted by 0.3 deg of yaw about gravity and
  // (1, -0.5, 0.7) cm per keyframe, i.e. 14 deg and 0.75 m at the end: what a visual-inertial odometry
  // can drift. The 4-DoF optimum is the truth.
  std::map<KeyframeId, Pose3> initial_T_wc;
  std::vector<PoseGraphEdge> edges;
  for (int k = 0; k < kVertices; ++k) {
    Pose3 drift = Pose3::Identity();
    drift.linear() = Eigen::AngleAxisd(0.3 * M_PI / 180.0 * k, kGravityDirectionW).toRotationMatrix();
    drift.translation() = k * Eigen::Vector3d(0.01, -0.005, 0.007);
    initial_T_wc[id_of(k)] = drift * inertial_true_pose(k);
    if (k > 0) {
      edges.push_back({id_of(k - 1), id_of(k), inertial_true_pose(k - 1).inverse() * inertial_true_pose(k), 1.0});
    }
  }
  edges.push_back(
      {id_of(kVertices - 1), id_of(0), inertial_true_pose(kVertices - 1).inverse() * inertial_true_pose(0), 1.0});
  ASSERT_GT(
      (initial_T_wc.at(id_of(kVertices - 1)).translation() - inertial_true_pose(kVertices - 1).translation()).norm(),
      0.5);

  const PoseGraphResult result = PoseGraph(four_dof_options()).compute(initial_T_wc, edges, {id_of(0)});
  double position_m = 0.0, rotation_rad = 0.0;
  for (int k = 0; k < kVertices; ++k) {
    const Pose3& T_wc = result.T_wc.at(id_of(k));
    position_m = std::max(position_m, (T_wc.translation() - inertial_true_pose(k).translation()).norm());
    rotation_rad = std::max(rotation_rad,
                            Eigen::AngleAxisd(T_wc.rotation().transpose() * inertial_true_pose(k).rotation()).angle());
  }
  const double gravity_change = largest_gravity_change(initial_T_wc, result.T_wc);
  std::printf("4-DoF, exact edges: from the truth %.3g m %.3g rad; gravity in the cameras moved %.3g; %d iterations\n",
              position_m, rotation_rad, gravity_change, result.stats.iterations);
  EXPECT_LT(position_m, 1e-9);
  EXPECT_LT(rotation_rad, 1e-9);
  EXPECT_LT(gravity_change, 1e-12);
  EXPECT_LT(result.stats.final_cost, 1e-20);
  EXPECT_EQ(result.T_wc.at(id_of(0)).matrix(), initial_T_wc.at(id_of(0)).matrix());
  EXPECT_EQ(result.stats.vertices, kVertices);
  EXPECT_EQ(result.stats.edges, kVertices);
}

TEST(LoopPoseGraph, FourDofKeepsRollAndPitchWhereTheSixDofGraphMovesThem) {
  // make_graph's odometry drifts in roll as well: the 6-DoF graph spreads that over the keyframes'
  // roll and pitch, the 4-DoF graph leaves gravity where the IMU put it and still closes the loop.
  const DriftedGraph graph = make_graph();
  const PoseGraphResult six = PoseGraph().compute(graph.initial_T_wc, graph.edges, {id_of(0)});
  const PoseGraphResult four = PoseGraph(four_dof_options()).compute(graph.initial_T_wc, graph.edges, {id_of(0)});
  const double six_change = largest_gravity_change(graph.initial_T_wc, six.T_wc);
  const double four_change = largest_gravity_change(graph.initial_T_wc, four.T_wc);
  const KeyframeId last = id_of(kVertices - 1);
  const Eigen::Vector3d true_end = true_pose(kVertices - 1).translation();
  const double initial_end_error_m = (graph.initial_T_wc.at(last).translation() - true_end).norm();
  const double four_end_error_m = (four.T_wc.at(last).translation() - true_end).norm();
  std::printf("gravity in the cameras moved: 6-DoF %.3g, 4-DoF %.3g; end error %.3f m -> %.3f m (4-DoF)\n", six_change,
              four_change, initial_end_error_m, four_end_error_m);
  EXPECT_GT(six_change, 1e-3);
  EXPECT_LT(four_change, 1e-12);
  EXPECT_LT(four.stats.final_cost, 0.5 * four.stats.initial_cost);
  EXPECT_LT(four_end_error_m * 5.0, initial_end_error_m);
  // Same input, same poses bit for bit.
  const PoseGraphResult again = PoseGraph(four_dof_options()).compute(graph.initial_T_wc, graph.edges, {id_of(0)});
  for (const auto& [id, T_wc] : four.T_wc) EXPECT_EQ(T_wc.matrix(), again.T_wc.at(id).matrix());
}

TEST(LoopPoseGraph, FourDofWithoutAGravityDirectionIsAnError) {
  const DriftedGraph graph = make_graph();
  PoseGraphOptions options = four_dof_options();
  options.gravity_w = Eigen::Vector3d::Zero();
  try {
    PoseGraph(options).compute(graph.initial_T_wc, graph.edges, {id_of(0)});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("gravity_w"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace heslam

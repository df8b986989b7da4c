// SE(3) pose graph on a circular trajectory with accumulated odometry drift and one loop edge.
#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace heslam

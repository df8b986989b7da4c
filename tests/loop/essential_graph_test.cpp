// Essential-graph edge selection on a hand-made map: which edges, measured on which poses.
#include <gtest/gtest.h>

#include "components/core/loop/essential_graph.hpp"

namespace heslam {
namespace {

Pose3 at(double x_m) {
  Pose3 T_wc = Pose3::Identity();
  T_wc.translation() = Eigen::Vector3d(x_m, 0.0, 0.0);
  return T_wc;
}

// Keyframes 1-2-3-4-5 in a spanning-tree chain, 1 m apart; 5 is culled.
Map chain_map() {
  Map map;
  for (KeyframeId id = 1; id <= 5; ++id) {
    Keyframe kf;
    kf.id = id;
    kf.T_wc = at(static_cast<double>(id - 1));
    kf.parent = id > 1 ? id - 1 : kNoId;
    map.keyframes.emplace(id, kf);
  }
  map.keyframes.at(5).culled = true;
  // Covisibility (kept symmetric, as the mapper does): 1-3 strong, 2-4 weak, 2-3 strong but a tree edge.
  const auto link = [&](KeyframeId a, KeyframeId b, int weight) {
    map.keyframes.at(a).covisible.emplace_back(b, weight);
    map.keyframes.at(b).covisible.emplace_back(a, weight);
  };
  link(1, 3, 150);
  link(2, 4, 99);
  link(2, 3, 300);
  link(3, 5, 200);  // to a culled keyframe
  return map;
}

const PoseGraphEdge* find_edge(const EssentialGraph& graph, KeyframeId a, KeyframeId b) {
  for (const PoseGraphEdge& e : graph.edges) {
    if ((e.from == a && e.to == b) || (e.from == b && e.to == a)) return &e;
  }
  return nullptr;
}

TEST(LoopEssentialGraph, SelectsTreeLoopAndStrongCovisibilityEdgesOnce) {
  const Map map = chain_map();
  const std::map<KeyframeId, Pose3> corrected{{4, at(0.5)}};  // the loop pulls keyframe 4 back to x = 0.5
  const std::vector<LoopConnection> connections{{4, 1, 10, true}, {4, 2, 99, false}, {4, 3, 120, false}};
  const EssentialGraph graph = EssentialGraphBuilder().compute(map, corrected, connections, {{1, 4}, {2, 5}});

  EXPECT_EQ(graph.new_loop_edges, 2);       // 4-1 (always) and 4-3 (>= 100); 4-2 too weak
  EXPECT_EQ(graph.spanning_tree_edges, 2);  // 1-2, 2-3; 3-4 is already a loop edge, 5 is culled
  EXPECT_EQ(graph.previous_loop_edges, 0);  // 1-4 already present, 2-5 culled
  EXPECT_EQ(graph.covisibility_edges, 1);   // 1-3; 2-4 too weak, 2-3 a tree edge, 3-5 culled
  EXPECT_EQ(graph.edges.size(), 5u);

  // New loop edges are measured on the corrected poses, the others on the map's.
  const PoseGraphEdge* loop_edge = find_edge(graph, 4, 1);
  ASSERT_NE(loop_edge, nullptr);
  EXPECT_NEAR(loop_edge->T_from_to.translation().x(), -0.5, 1e-12);
  const PoseGraphEdge* covisibility_edge = find_edge(graph, 1, 3);
  ASSERT_NE(covisibility_edge, nullptr);
  const double expected_x = covisibility_edge->from == 1 ? 2.0 : -2.0;
  EXPECT_NEAR(covisibility_edge->T_from_to.translation().x(), expected_x, 1e-12);
  EXPECT_EQ(find_edge(graph, 2, 4), nullptr);
}

TEST(LoopEssentialGraph, WeightThresholdIsAnOption) {
  const Map map = chain_map();
  EssentialGraphOptions options;
  options.min_covisibility_weight = 50;
  const EssentialGraph graph = EssentialGraphBuilder(options).compute(map, {}, {}, {});
  EXPECT_EQ(graph.spanning_tree_edges, 3);
  EXPECT_EQ(graph.covisibility_edges, 2);  // 1-3 and now 2-4
}

}  // namespace
}  // namespace heslam

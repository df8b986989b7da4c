// Essential-graph edge selection: new loop, spanning tree, previous loop and strong covisibility edges.
#include "components/core/loop/essential_graph.hpp"

#include <algorithm>
#include <set>

namespace heslam {

EssentialGraph EssentialGraphBuilder::compute(
    const Map& map, const std::map<KeyframeId, Pose3>& corrected_T_wc,
    const std::vector<LoopConnection>& new_loop_connections,
    const std::vector<std::pair<KeyframeId, KeyframeId>>& previous_loop_edges) const {
  EssentialGraph graph;
  std::set<std::pair<KeyframeId, KeyframeId>> inserted;  // (smaller id, larger id)
  const auto live = [&](KeyframeId id) {
    const Keyframe* kf = map.keyframe(id);
    return kf != nullptr && !kf->culled;
  };
  // Adds from -> to measured on the given poses, once per unordered pair.
  const auto add = [&](KeyframeId from, KeyframeId to, const Pose3& T_w_from, const Pose3& T_w_to) {
    if (from == to || !live(from) || !live(to)) return false;
    if (!inserted.emplace(std::min(from, to), std::max(from, to)).second) return false;
    graph.edges.push_back({from, to, T_w_from.inverse() * T_w_to, 1.0});
    return true;
  };
  const auto corrected = [&](KeyframeId id) -> Pose3 {
    const auto it = corrected_T_wc.find(id);
    return it != corrected_T_wc.end() ? it->second : map.keyframe(id)->T_wc;
  };
  const auto original = [&](KeyframeId id) -> const Pose3& { return map.keyframe(id)->T_wc; };

  for (const LoopConnection& connection : new_loop_connections) {
    if (!connection.always && connection.shared_points < options_.min_covisibility_weight) continue;
    if (!live(connection.from) || !live(connection.to)) continue;
    const KeyframeId from = connection.from;
    const KeyframeId to = connection.to;
    if (add(from, to, corrected(from), corrected(to))) ++graph.new_loop_edges;
  }
  for (const auto& [id, kf] : map.keyframes) {
    if (kf.culled || kf.parent == kNoId || !live(kf.parent)) continue;
    if (add(kf.parent, id, original(kf.parent), original(id))) ++graph.spanning_tree_edges;
  }
  for (const auto& [a, b] : previous_loop_edges) {
    if (!live(a) || !live(b)) continue;
    if (add(a, b, original(a), original(b))) ++graph.previous_loop_edges;
  }
  for (const auto& [id, kf] : map.keyframes) {
    if (kf.culled) continue;
    for (const auto& [neighbour, weight] : kf.covisible) {
      if (weight < options_.min_covisibility_weight || !live(neighbour)) continue;
      if (add(id, neighbour, original(id), original(neighbour))) ++graph.covisibility_edges;
    }
  }
  return graph;
}

}  // namespace heslam

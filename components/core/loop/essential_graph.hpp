// The essential graph of a map: the sparse set of relative-pose constraints the loop closer
// optimizes (ORB-SLAM2's OptimizeEssentialGraph edge selection).
//
// Edges, each keyframe pair at most once, in this order:
//   1. new loop edges (the loop closure's connections), measured on the CORRECTED poses: they carry
//      the correction into the graph;
//   2. spanning-tree edges (Keyframe::parent), 3. previous loop edges, 4. covisibility edges with at
//   least `min_covisibility_weight` shared points; all measured on the map's (uncorrected) poses, so
//   they keep the trajectory's local shape.
// Culled keyframes take no part.
#pragma once

#include <map>
#include <utility>
#include <vector>

#include "components/core/loop/pose_graph.hpp"
#include "components/core/map/map.hpp"

namespace heslam {

// A covisibility link created by the loop closure (after its point fusion).
struct LoopConnection {
  KeyframeId from = kNoId;
  KeyframeId to = kNoId;
  int shared_points = 0;
  bool always = false;  // the loop keyframe - matched keyframe link: kept whatever its weight
};

struct EssentialGraphOptions {
  int min_covisibility_weight = 100;  // ORB-SLAM2's minFeat: only strong covisibility constrains
};

struct EssentialGraph {
  std::vector<PoseGraphEdge> edges;
  int new_loop_edges = 0;
  int spanning_tree_edges = 0;
  int previous_loop_edges = 0;
  int covisibility_edges = 0;
};

class EssentialGraphBuilder {
 public:
  explicit EssentialGraphBuilder(const EssentialGraphOptions& options = {}) : options_(options) {}

  // `corrected_T_wc`: the loop-corrected poses of some keyframes (the loop keyframe's group); new
  // loop edges use them where given, the map's poses elsewhere. `previous_loop_edges`: keyframe pairs
  // of earlier loop closures.
  EssentialGraph compute(const Map& map, const std::map<KeyframeId, Pose3>& corrected_T_wc,
                         const std::vector<LoopConnection>& new_loop_connections,
                         const std::vector<std::pair<KeyframeId, KeyframeId>>& previous_loop_edges) const;

 private:
  EssentialGraphOptions options_;
};

}  // namespace heslam

// Covisibility graph and spanning tree upkeep (ORB-SLAM2's KeyFrame::UpdateConnections).
//
// Edge weight = number of map points two keyframes both observe. Keyframe::covisible is kept sorted
// by weight (descending), ties by id, so neighbour selection is deterministic.
#pragma once

#include <set>
#include <vector>

#include "components/core/map/map.hpp"
#include "components/core/mapping/local_mapper_options.hpp"

namespace heslam {

// Recounts the shared points of `kf_id` with every other live keyframe, stores the edges with at
// least `min_shared_points` (or the single strongest one if none reaches it) on both ends, and gives
// a parentless keyframe its strongest neighbour as spanning-tree parent. Returns the keyframes whose
// covisibility list or parent changed, including `kf_id`.
std::set<KeyframeId> update_connections(Map& map, KeyframeId kf_id, const CovisibilityOptions& options);

// The `count` strongest live neighbours of a keyframe (fewer when it has fewer).
std::vector<KeyframeId> best_covisible(const Map& map, KeyframeId kf_id, int count);

}  // namespace heslam

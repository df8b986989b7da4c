// Covisibility edges and spanning-tree parent from shared map points.
#include "components/core/mapping/covisibility.hpp"

#include <algorithm>
#include <map>

namespace heslam {
namespace {

void sort_edges(std::vector<std::pair<KeyframeId, int>>& edges) {
  std::sort(edges.begin(), edges.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
}

// Sets (or removes, when weight == 0) the edge to `other` in `kf`'s list. True if it changed.
bool set_edge(Keyframe& kf, KeyframeId other, int weight) {
  auto it = std::find_if(kf.covisible.begin(), kf.covisible.end(), [other](const auto& e) { return e.first == other; });
  if (it != kf.covisible.end()) {
    if (it->second == weight) return false;
    if (weight == 0) {
      kf.covisible.erase(it);
    } else {
      it->second = weight;
    }
  } else {
    if (weight == 0) return false;
    kf.covisible.emplace_back(other, weight);
  }
  sort_edges(kf.covisible);
  return true;
}

}  // namespace

std::set<KeyframeId> update_connections(Map& map, KeyframeId kf_id, const CovisibilityOptions& options) {
  std::set<KeyframeId> touched;
  Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled) return touched;

  std::map<KeyframeId, int> shared;
  for (const PointId point_id : kf->point_ids) {
    if (point_id == kNoId) continue;
    const MapPoint* point = map.point(point_id);
    if (point == nullptr) continue;
    for (const auto& [other, index] : point->observations) {
      if (other != kf_id) ++shared[other];
    }
  }

  std::vector<std::pair<KeyframeId, int>> edges;
  KeyframeId strongest = kNoId;
  int strongest_weight = 0;
  for (const auto& [other, weight] : shared) {
    const Keyframe* neighbour = map.keyframe(other);
    if (neighbour == nullptr || neighbour->culled) continue;
    if (weight > strongest_weight) {
      strongest_weight = weight;
      strongest = other;
    }
    if (weight >= options.min_shared_points) edges.emplace_back(other, weight);
  }
  if (edges.empty() && strongest != kNoId) edges.emplace_back(strongest, strongest_weight);
  sort_edges(edges);

  // Neighbours that lost the edge drop it too, so the graph stays symmetric.
  for (const auto& [old_neighbour, weight] : kf->covisible) {
    const bool kept = std::any_of(edges.begin(), edges.end(), [&](const auto& e) { return e.first == old_neighbour; });
    Keyframe* neighbour = map.keyframe(old_neighbour);
    if (!kept && neighbour != nullptr && set_edge(*neighbour, kf_id, 0)) touched.insert(old_neighbour);
  }
  for (const auto& [other, weight] : edges) {
    if (set_edge(*map.keyframe(other), kf_id, weight)) touched.insert(other);
  }
  if (kf->covisible != edges) {
    kf->covisible = edges;
    touched.insert(kf_id);
  }
  if (kf->parent == kNoId && !edges.empty() && kf_id != map_origin(map, kf->map_id)) {
    kf->parent = edges.front().first;
    touched.insert(kf_id);
  }
  return touched;
}

std::vector<KeyframeId> best_covisible(const Map& map, KeyframeId kf_id, int count) {
  std::vector<KeyframeId> result;
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr) return result;
  for (const auto& [other, weight] : kf->covisible) {
    if (static_cast<int>(result.size()) >= count) break;
    const Keyframe* neighbour = map.keyframe(other);
    if (neighbour != nullptr && !neighbour->culled) result.push_back(other);
  }
  return result;
}

}  // namespace heslam

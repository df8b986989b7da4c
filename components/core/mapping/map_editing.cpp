// Link-consistent edits of the Map.
#include "components/core/mapping/map_editing.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <utility>

namespace heslam {

void add_observation(Map& map, PointId point_id, KeyframeId kf_id, int index) {
  MapPoint* point = map.point(point_id);
  Keyframe* kf = map.keyframe(kf_id);
  if (point == nullptr || kf == nullptr || index < 0 || index >= static_cast<int>(kf->point_ids.size())) {
    throw std::logic_error("add_observation: unknown point, keyframe or keypoint index " + std::to_string(index));
  }
  if (observation_index(*point, kf_id) >= 0) return;
  kf->point_ids[index] = point_id;
  point->observations.emplace_back(kf_id, index);
}

int observation_index(const MapPoint& point, KeyframeId kf_id) {
  for (const auto& [id, index] : point.observations) {
    if (id == kf_id) return index;
  }
  return -1;
}

void erase_observation(Map& map, PointId point_id, KeyframeId kf_id) {
  MapPoint* point = map.point(point_id);
  if (point == nullptr) return;
  auto& obs = point->observations;
  for (auto it = obs.begin(); it != obs.end(); ++it) {
    if (it->first != kf_id) continue;
    if (Keyframe* kf = map.keyframe(kf_id); kf != nullptr && kf->point_ids[it->second] == point_id) {
      kf->point_ids[it->second] = kNoId;
    }
    obs.erase(it);
    break;
  }
  if (point->reference_kf == kf_id) point->reference_kf = obs.empty() ? kNoId : obs.front().first;
}

void erase_point(Map& map, PointId point_id) {
  MapPoint* point = map.point(point_id);
  if (point == nullptr) return;
  for (const auto& [kf_id, index] : point->observations) {
    if (Keyframe* kf = map.keyframe(kf_id); kf != nullptr && kf->point_ids[index] == point_id) {
      kf->point_ids[index] = kNoId;
    }
  }
  map.points.erase(point_id);
}

void replace_point(Map& map, PointId from, PointId into) {
  if (from == into) return;
  MapPoint* source = map.point(from);
  MapPoint* target = map.point(into);
  if (source == nullptr || target == nullptr) return;
  for (const auto& [kf_id, index] : source->observations) {
    Keyframe* kf = map.keyframe(kf_id);
    if (kf == nullptr) continue;
    if (observation_index(*target, kf_id) < 0) {
      kf->point_ids[index] = into;
      target->observations.emplace_back(kf_id, index);
    } else {
      kf->point_ids[index] = kNoId;
    }
  }
  target->found += source->found;
  target->visible += source->visible;
  map.points.erase(from);
}

void cull_keyframe(Map& map, KeyframeId kf_id, MapChanges& changes) {
  std::set<KeyframeId>& changed_keyframes = changes.changed_keyframes;
  Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled) return;
  const std::vector<PointId> point_ids = kf->point_ids;
  for (const PointId point_id : point_ids) {
    if (point_id == kNoId) continue;
    erase_observation(map, point_id, kf_id);
    const MapPoint* point = map.point(point_id);
    if (point != nullptr && observation_weight(map, *point) <= 2) {
      erase_point(map, point_id);
      changes.changed_points.erase(point_id);
      changes.removed_points[point_id] = kNoId;
    } else {
      changes.changed_points.insert(point_id);
    }
  }
  for (const auto& [neighbour_id, weight] : kf->covisible) {
    Keyframe* neighbour = map.keyframe(neighbour_id);
    if (neighbour == nullptr) continue;
    std::erase_if(neighbour->covisible, [kf_id](const auto& edge) { return edge.first == kf_id; });
    changed_keyframes.insert(neighbour_id);
  }

  // Reattach children: ORB-SLAM2 repeatedly picks the (child, candidate parent) pair with the
  // strongest covisibility, where candidates are the culled keyframe's parent and the children
  // already reattached; a child with no covisible candidate goes to the culled keyframe's parent.
  std::vector<KeyframeId> children;
  for (const auto& [id, other] : map.keyframes) {
    if (other.parent == kf_id && !other.culled && id != kf_id) children.push_back(id);
  }
  std::set<KeyframeId> candidates;
  if (kf->parent != kNoId) candidates.insert(kf->parent);
  while (!children.empty()) {
    int best_weight = -1;
    std::size_t best_child = 0;
    KeyframeId best_parent = kNoId;
    for (std::size_t c = 0; c < children.size(); ++c) {
      for (const auto& [neighbour_id, weight] : map.keyframes.at(children[c]).covisible) {
        if (candidates.count(neighbour_id) != 0 && weight > best_weight) {
          best_weight = weight;
          best_child = c;
          best_parent = neighbour_id;
        }
      }
    }
    if (best_weight < 0) break;
    map.keyframes.at(children[best_child]).parent = best_parent;
    changed_keyframes.insert(children[best_child]);
    candidates.insert(children[best_child]);
    children.erase(children.begin() + static_cast<std::ptrdiff_t>(best_child));
  }
  for (const KeyframeId child : children) {
    map.keyframes.at(child).parent = kf->parent;
    changed_keyframes.insert(child);
  }

  std::vector<std::pair<KeyframeId, int>>().swap(kf->covisible);
  kf->culled = true;
  release_culled_keyframe(*kf);
  changed_keyframes.insert(kf_id);
}

}  // namespace heslam

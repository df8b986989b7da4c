// Redundant keyframes among the new keyframe's covisible neighbours.
#include "components/core/mapping/keyframe_culling.hpp"

#include "components/core/mapping/map_editing.hpp"

namespace heslam {

bool is_redundant_keyframe(const Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                           const KeyframeCullingOptions& options) {
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled) return false;
  const double close_depth_m = options.close_depth_baselines * camera.baseline_m;
  int counted = 0;
  int redundant = 0;
  for (std::size_t i = 0; i < kf->point_ids.size(); ++i) {
    const MapPoint* point = kf->point_ids[i] == kNoId ? nullptr : map.point(kf->point_ids[i]);
    if (point == nullptr) continue;
    // Stereo: far points (or keypoints without depth) say little about this keyframe's value.
    const float depth = kf->features.depth_m[i];
    if (depth > close_depth_m || depth < 0.f) continue;
    ++counted;
    if (static_cast<int>(point->observations.size()) <= options.min_other_observers) continue;
    const int level = kf->features.keypoints[i].octave;
    int observers = 0;
    for (const auto& [other_id, index] : point->observations) {
      if (other_id == kf_id) continue;
      const Keyframe* other = map.keyframe(other_id);
      if (other == nullptr || other->culled) continue;
      // Same or finer scale: a level at most one above ours (ORB-SLAM2).
      if (other->features.keypoints[static_cast<std::size_t>(index)].octave <= level + 1) ++observers;
      if (observers >= options.min_other_observers) break;
    }
    if (observers >= options.min_other_observers) ++redundant;
  }
  return counted > 0 && redundant > options.redundant_ratio * counted;
}

std::vector<KeyframeId> cull_redundant_neighbours(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                  const KeyframeCullingOptions& options, MapChanges& changes) {
  std::vector<KeyframeId> culled;
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || map.keyframes.empty()) return culled;
  const KeyframeId origin_id = map_origin(map, kf->map_id);  // each map of the atlas has its own
  const auto neighbours = kf->covisible;                     // culling edits the lists
  for (const auto& [neighbour, weight] : neighbours) {
    if (neighbour == origin_id || neighbour == kf_id) continue;
    if (!is_redundant_keyframe(map, neighbour, camera, options)) continue;
    cull_keyframe(map, neighbour, changes);
    culled.push_back(neighbour);
  }
  return culled;
}

}  // namespace heslam

// Derived state of a map point from its observations: representative descriptor, mean viewing
// direction and the distance range over which ORB can re-detect it (ORB-SLAM2's
// ComputeDistinctiveDescriptors and UpdateNormalAndDepth).
#pragma once

#include <unordered_map>

#include "components/core/map/map.hpp"

namespace heslam {

// Recomputes descriptor, normal and distance range; no-op for a point without observations.
void update_point_statistics(Map& map, PointId point_id);

// The map's keyframes by id in a hash table: for updating many points at once (a loop correction
// moves every point) without a tree search per observation. Valid while no keyframe is added or
// removed from the map.
class KeyframeIndex {
 public:
  explicit KeyframeIndex(const Map& map);
  const Keyframe* find(KeyframeId id) const {
    const auto it = keyframes_.find(id);
    return it == keyframes_.end() ? nullptr : it->second;
  }

 private:
  std::unordered_map<KeyframeId, const Keyframe*> keyframes_;
};

// The same as update_point_statistics(map, id), with the keyframes looked up in `index`.
void update_point_statistics(MapPoint& point, const KeyframeIndex& index);

// Only the normal and the distance range, for a point that moved while its observations did not (a
// loop correction): the descriptor depends on the observations alone (ORB-SLAM2's CorrectLoop calls
// UpdateNormalAndDepth alone too).
void update_point_geometry(MapPoint& point, const KeyframeIndex& index);

// The observation's descriptor with the least median Hamming distance to the others.
Descriptor representative_descriptor(const Map& map, const MapPoint& point);

// Pyramid level at which a point at `distance_m` is expected to be detected (ORB-SLAM2
// PredictScale), clamped to the pyramid.
int predict_level(const MapPoint& point, double distance_m, const ScalePyramid& pyramid);

}  // namespace heslam

// The map data model: keyframes, map points and their ids, as plain values.
//
// One process owns one Map (the mapper owns the real one, the frontend a mirror); there are no
// locks because no Map is shared between threads. Containers are ordered by id so every iteration
// is deterministic (lockstep runs must be bit-identical).
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "components/core/feature/features.hpp"
#include "components/core/geometry/pose.hpp"
#include "components/core/map/ids.hpp"

namespace heslam {

using KeyframeId = std::uint64_t;
using PointId = std::uint64_t;
inline constexpr std::uint64_t kNoId = 0;

// The atlas (docs/frontend.md, Atlas): one Map holds several maps as a partition by map id. Every
// keyframe and point carries its map's id; no observation, covisibility edge or spanning-tree edge
// crosses two maps, so local BA, culling and covisibility stay inside one map without further checks.
// The first map is 0 (so a map file or a message from before the atlas reads as the first map); the
// frontend numbers the maps it starts after a loss 1, 2, ...
using MapId = std::uint32_t;
inline constexpr MapId kFirstMapId = 0;

// Ids: make_id(creator_tag, counter), creator tags and format_id() are in ids.hpp.

struct Keyframe {
  KeyframeId id = kNoId;
  MapId map_id = kFirstMapId;
  std::int64_t stamp_ns = 0;
  Pose3 T_wc = Pose3::Identity();
  StereoFeatures features;
  std::vector<PointId> point_ids;  // per keypoint: the observed map point, or kNoId

  // State owned by the local mapper after creation.
  KeyframeId parent = kNoId;                          // spanning tree
  std::vector<std::pair<KeyframeId, int>> covisible;  // (neighbour, shared points), by weight desc
  bool culled = false;
};

struct MapPoint {
  PointId id = kNoId;
  MapId map_id = kFirstMapId;  // its observers' map
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  Descriptor descriptor{};                           // representative (median-distance) descriptor
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // mean viewing direction, unit
  float min_distance_m = 0.f;                        // scale-invariance range
  float max_distance_m = 0.f;
  KeyframeId reference_kf = kNoId;
  std::vector<std::pair<KeyframeId, int>> observations;  // (keyframe, keypoint index)
  int visible = 1;                                       // times predicted visible in a frame
  int found = 1;                                         // times actually matched
  bool culled = false;
  PointId merged_into = kNoId;
};

struct Map {
  std::map<KeyframeId, Keyframe> keyframes;
  std::map<PointId, MapPoint> points;
  std::uint64_t version = 0;  // bumped on every change the mapper publishes

  Keyframe* keyframe(KeyframeId id) {
    auto it = keyframes.find(id);
    return it == keyframes.end() ? nullptr : &it->second;
  }
  MapPoint* point(PointId id) {
    auto it = points.find(id);
    return it == points.end() ? nullptr : &it->second;
  }
  const Keyframe* keyframe(KeyframeId id) const {
    auto it = keyframes.find(id);
    return it == keyframes.end() ? nullptr : &it->second;
  }
  const MapPoint* point(PointId id) const {
    auto it = points.find(id);
    return it == points.end() ? nullptr : &it->second;
  }
};

// The root of map `map_id`'s spanning tree: its oldest keyframe (the first map's is the whole store's
// oldest, as before the atlas), kNoId when the map has none. Local BA holds it fixed and culling keeps
// it, per map. Keyframe ids grow with time and a new map starts with a new keyframe, so the first
// keyframe found in id order is the map's first.
inline KeyframeId map_origin(const Map& map, MapId map_id) {
  for (const auto& [id, keyframe] : map.keyframes) {
    if (keyframe.map_id == map_id) return id;
  }
  return kNoId;
}

// A culled keyframe (ORB-SLAM's SetBadFlag) keeps its id, map, stamp, pose and parent: frames that
// referenced it keep their anchor, and corrections move it. Its features and point slots go, with
// their memory (not only their size), in the mapper and in every mirror, so each process's memory
// follows the keyframes kept, not every keyframe ever made (issue 41, docs/mapping.md).
inline void release_culled_keyframe(Keyframe& keyframe) {
  StereoFeatures released;
  released.pyramid = keyframe.features.pyramid;
  keyframe.features = std::move(released);
  std::vector<PointId>().swap(keyframe.point_ids);
}

// A point's observations counted as ORB-SLAM2's MapPoint::Observations(): 2 for a keypoint with stereo
// depth, 1 otherwise. Its thresholds (point culling, the reference keyframe's tracked points) are in
// these units.
inline int observation_weight(const Map& map, const MapPoint& point) {
  int weight = 0;
  for (const auto& [kf_id, index] : point.observations) {
    const Keyframe* kf = map.keyframe(kf_id);
    if (kf == nullptr) continue;
    weight += kf->features.has_stereo(static_cast<std::size_t>(index)) ? 2 : 1;
  }
  return weight;
}

}  // namespace heslam

// Edits of the Map that keep the two directions of a keyframe <-> point link consistent:
// Keyframe::point_ids[index] == point.id  <=>  (keyframe.id, index) in point.observations.
#pragma once

#include <set>

#include "components/core/map/map.hpp"
#include "components/core/mapping/map_changes.hpp"

namespace heslam {

// Links keypoint `index` of `kf_id` to `point_id` (both must exist; the keypoint must be free).
void add_observation(Map& map, PointId point_id, KeyframeId kf_id, int index);

// Unlinks the point from the keyframe (no-op when not linked).
void erase_observation(Map& map, PointId point_id, KeyframeId kf_id);

// Index of the keypoint of `kf_id` observing `point_id`, or -1.
int observation_index(const MapPoint& point, KeyframeId kf_id);

// Unlinks the point from every keyframe and removes it from the map.
void erase_point(Map& map, PointId point_id);

// Moves every observation of `from` to `into` (dropping those whose keyframe already sees `into`),
// adds the found / visible counts and removes `from`. ORB-SLAM2's MapPoint::Replace.
void replace_point(Map& map, PointId from, PointId into);

// Marks a keyframe culled: unlinks all its points, drops it from its neighbours' covisibility lists
// and reattaches its spanning-tree children (ORB-SLAM2's KeyFrame::SetBadFlag). The keyframe stays
// in the map, culled, with its pose and parent, so trajectories through it can still be resolved.
// Points left with an observation weight <= 2 are erased, as ORB-SLAM2 does. Records every
// changed keyframe (neighbours, reparented children, itself) and changed / removed point in `changes`.
void cull_keyframe(Map& map, KeyframeId kf_id, MapChanges& changes);

}  // namespace heslam

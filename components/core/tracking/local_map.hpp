// The tracker's view of the map around the current frame (ORB-SLAM2 UpdateLocalKeyFrames / Points),
// and the bookkeeping the tracker does itself when no local mapper runs.
#pragma once

#include <vector>

#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

struct LocalMapSelection {
  std::vector<KeyframeId> keyframes;  // keyframes sharing points with the frame, then their neighbours
  std::vector<PointId> points;        // every point they observe, once, ascending id (culled ones too)
  KeyframeId reference = kNoId;       // the keyframe sharing most points with the frame
};

// Keyframes that observe the frame's matched points, plus their best covisible neighbours and parents,
// capped at options.local_map_max_keyframes; their points form the local map.
LocalMapSelection select_local_map(const Frame& frame, const Map& map, const TrackerOptions& options);

// Builds the new keyframe's map-point content from the frame: tracked points as observations, new
// stereo points for close untracked features (ORB-SLAM2 CreateNewKeyFrame). Ids from the counters;
// the keyframe and its new points belong to map `map_id`.
struct KeyframeCandidate {
  Keyframe keyframe;
  std::vector<MapPoint> new_points;
};
KeyframeCandidate make_keyframe(const Frame& frame, const PinholeStereo& camera, const Map& map, KeyframeId keyframe_id,
                                std::uint64_t& next_point_counter, const TrackerOptions& options,
                                MapId map_id = kFirstMapId);

// Inserts a keyframe and its new points into the map. With options.maintain_map (no mapper) it also
// records the keyframe's observations of existing points, refreshes their normals, distance ranges and
// descriptors (and, with options.fuse_stereo_observations, positions), and links the keyframe into the
// covisibility graph and spanning tree.
void insert_keyframe(Map& map, const KeyframeCandidate& candidate, const PinholeStereo& camera,
                     const TrackerOptions& options);

// Fills a new point's normal, distance range and reference from the keyframe that created it.
void init_point_geometry(MapPoint& point, const Keyframe& keyframe, int keypoint_index);

}  // namespace heslam

// Redundant keyframe detection (ORB-SLAM2's LocalMapping::KeyFrameCulling): a covisible keyframe
// whose close map points are ~90 % observed by at least three other keyframes at the same or a finer
// scale adds little and is culled, which keeps the map size proportional to the explored space.
#pragma once

#include <set>
#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/local_mapper_options.hpp"
#include "components/core/mapping/map_changes.hpp"

namespace heslam {

// True when the keyframe is redundant by the rule above.
bool is_redundant_keyframe(const Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                           const KeyframeCullingOptions& options);

// The share of keyframe `kf_id`'s tracked points (those another keyframe observes too; call it just
// after inserting the keyframe, before triangulation) that a keyframe made at least min_age_s before
// it observes; 0 without tracked points.
double old_map_share(const Map& map, KeyframeId kf_id, double min_age_s);

// Whether keyframe `kf_id`, just inserted, was made on a place mapped before (the revisit rule above).
bool is_revisit_keyframe(const Map& map, KeyframeId kf_id, const KeyframeCullingOptions& options);

// Culls, one after the other in covisibility order, the covisible keyframes of `kf_id` that are
// redundant once the previous ones are gone, or that are in `revisits` (made on a revisit, culled
// once a newer keyframe is mapped next to them); never the map's first keyframe nor `kf_id` itself.
// Returns the culled ids; every state change is recorded in `changes`.
std::vector<KeyframeId> cull_redundant_neighbours(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                  const KeyframeCullingOptions& options, MapChanges& changes,
                                                  const std::set<KeyframeId>& revisits = {});

}  // namespace heslam

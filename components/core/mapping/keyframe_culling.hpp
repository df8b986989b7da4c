// Redundant keyframe detection (ORB-SLAM2's LocalMapping::KeyFrameCulling): a covisible keyframe
// whose close map points are ~90 % observed by at least three other keyframes at the same or a finer
// scale adds little and is culled, which keeps the map size proportional to the explored space.
#pragma once

#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/mapping/local_mapper_options.hpp"
#include "components/core/mapping/map_changes.hpp"

namespace heslam {

// True when the keyframe is redundant by the rule above.
bool is_redundant_keyframe(const Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                           const KeyframeCullingOptions& options);

// Culls, one after the other in covisibility order, the covisible keyframes of `kf_id` that are
// redundant once the previous ones are gone (never the map's first keyframe nor `kf_id` itself).
// Returns the culled ids; every state change is recorded in `changes`.
std::vector<KeyframeId> cull_redundant_neighbours(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                                  const KeyframeCullingOptions& options, MapChanges& changes);

}  // namespace heslam

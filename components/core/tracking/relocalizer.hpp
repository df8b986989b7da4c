// Recovering the pose of a lost frame against recent keyframes: descriptor matching (no bag of words
// yet), seeded PnP RANSAC, motion-only BA, then a projection search to confirm with many inliers.
#pragma once

#include <optional>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

struct Relocalization {
  KeyframeId keyframe = kNoId;  // the keyframe the frame was relocalized against
  int inliers = 0;
};

// On success the frame holds the recovered pose and its inlier matches; on failure it is left without
// matches and its pose untouched. Deterministic: RANSAC is seeded from options and the frame's seq.
std::optional<Relocalization> relocalize(Frame& frame, Map& map, const PinholeStereo& camera,
                                         const TrackerOptions& options);

}  // namespace heslam

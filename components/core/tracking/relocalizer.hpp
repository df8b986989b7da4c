// Recovering the pose of a lost frame (ORB-SLAM2 Relocalization): candidate keyframes from the keyframe
// database (bag of words), BoW matching against each in order, seeded PnP RANSAC, motion-only BA, then
// a projection search to confirm with many inliers. Without a database (no vocabulary configured) the
// newest keyframes are tried with brute-force matching instead.
#pragma once

#include <optional>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/place/keyframe_database.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

struct Relocalization {
  KeyframeId keyframe = kNoId;  // the keyframe the frame was relocalized against
  int inliers = 0;
  int candidates_tried = 0;  // keyframes matched against before this one succeeded (this one included)
};

// On success the frame holds the recovered pose and its inlier matches; on failure it is left without
// matches and its pose untouched. Deterministic: candidates come ordered, RANSAC is seeded from options,
// the frame's seq and the keyframe id. `database` (may be null: newest keyframes, brute force) must be
// in sync with `map` (KeyframeDatabase::sync).
std::optional<Relocalization> relocalize(Frame& frame, Map& map, const PinholeStereo& camera,
                                         const TrackerOptions& options, const KeyframeDatabase* database = nullptr);

}  // namespace heslam

// Matching map points to the keypoints of the current frame (ORB-SLAM2 ORBmatcher, without BoW):
//   - from the last frame, by projecting its tracked points with the motion-model pose;
//   - from the local map, with visibility, scale-range and viewing-angle checks;
//   - from a keyframe, guided by a pose guess or by brute force with a ratio test.
// Each writes matches into Frame::point_ids (never over an existing match) and returns how many it added.
#pragma once

#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

// Motion model search: last frame's tracked points projected with current.T_wc; window radius_px times
// the keypoint scale, pyramid levels restricted by the direction of motion along the optical axis.
int search_from_last_frame(Frame& current, const Frame& last, const Map& map, const PinholeStereo& camera,
                           float radius_px, const TrackerOptions& options);

// Local map search: points (not yet matched in `current`) projected with current.T_wc. Increments the
// `visible` counter of every point predicted in view (as ORB-SLAM2 does), so the map is non-const.
int search_local_points(Frame& current, const std::vector<PointId>& local_points, Map& map, const PinholeStereo& camera,
                        float radius_px, const TrackerOptions& options);

// Guided keyframe search: the keyframe's points projected with current.T_wc in a wide window, best match
// kept only if clearly better than the second (ratio) and within TH_HIGH.
int search_keyframe_by_projection(Frame& current, const Keyframe& keyframe, const Map& map, const PinholeStereo& camera,
                                  float radius_px, float ratio, const TrackerOptions& options);

// Pose-free keyframe search: every keyframe point against every unmatched keypoint, TH_LOW and ratio.
int search_keyframe_brute_force(Frame& current, const Keyframe& keyframe, const Map& map, float ratio,
                                const TrackerOptions& options);

}  // namespace heslam

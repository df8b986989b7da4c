// Whether the current frame should become a keyframe (ORB-SLAM2 Tracking::NeedNewKeyFrame, stereo rules).
#pragma once

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

struct KeyframeDecisionInput {
  int frames_since_keyframe = 0;       // frames tracked since the last keyframe was inserted
  int frames_since_relocalization = 0;  // large when never relocalized
  int tracked_inliers = 0;              // map points matched by the local map search, after optimization
  int keyframes_in_map = 0;
  int reference_tracked_points = 0;     // reference keyframe's points with enough observations
  // Of those two counts, the ones whose feature is near a clip edge (StereoFeatures::near_clip): they
  // count TrackerOptions::reference_near_clip_weight in the reference-ratio rule.
  int tracked_inliers_near_clip = 0;
  int reference_points_near_clip = 0;
  bool mapper_idle = true;
};

struct KeyframeDecision {
  bool insert = false;
  int tracked_close = 0;    // close stereo features matched to map points
  int untracked_close = 0;  // close stereo features that would become new points
};

// Minimum observation_weight (map.hpp: a stereo observation counts 2) for a reference point to count,
// as ORB-SLAM2's KeyFrame::TrackedMapPoints: 3, or 2 while the map is tiny.
int reference_min_observations(int keyframes_in_map);
int count_reference_points(const Keyframe& reference, const Map& map, int min_observations);
// Of count_reference_points' points, those whose keyframe feature is near a clip edge.
int count_reference_points_near_clip(const Keyframe& reference, const Map& map, int min_observations);
// The frame's matched map points whose feature is near a clip edge.
int count_tracked_near_clip(const Frame& frame);

KeyframeDecision decide_keyframe(const Frame& frame, const PinholeStereo& camera, const KeyframeDecisionInput& input,
                                 const TrackerOptions& options);

}  // namespace heslam

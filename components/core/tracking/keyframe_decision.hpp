// Whether the current frame should become a keyframe (ORB-SLAM2 Tracking::NeedNewKeyFrame, stereo rules).
#pragma once

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"
#include "components/core/tracking/frame.hpp"
#include "components/core/tracking/tracker_options.hpp"

namespace heslam {

struct KeyframeDecisionInput {
  int frames_since_keyframe = 0;        // frames tracked since the last keyframe was inserted
  int frames_since_relocalization = 0;  // large when never relocalized
  int tracked_inliers = 0;              // map points matched by the local map search, after optimization
  int keyframes_in_map = 0;
  int reference_tracked_points = 0;  // reference keyframe's points with enough observations
  // Of those two counts, the ones whose feature is near a clip edge (StereoFeatures::near_clip): they
  // count TrackerOptions::reference_near_clip_weight in the reference-ratio rule.
  int tracked_inliers_near_clip = 0;
  int reference_points_near_clip = 0;
  bool mapper_idle = true;
  // The frame is near a keyframe made long before it (TrackerOptions::revisit_*; revisit_covered()).
  bool revisit_covered = false;
};

struct KeyframeDecision {
  bool insert = false;
  int tracked_close = 0;    // close stereo features matched to map points
  int untracked_close = 0;  // close stereo features that would become new points
  bool covered = false;     // the rules asked for a keyframe, but the place is mapped (revisit_covered)
};

// How a reference keyframe's point is counted against reference_min_observations.
enum class ObservationCount {
  // A local mapper's map (mirrored): observation_weight (map.hpp, a stereo observation counts 2), as
  // ORB-SLAM2's KeyFrame::TrackedMapPoints, whose threshold presumes its mapper (points of weight 3 or
  // less culled, triangulation and fusion adding observations). Counting keyframes there instead left
  // out points seen in stereo by two keyframes: too few keyframes, more drift at the corridor's turns
  // (docs/benchmarks.md, Open-loop drift).
  weighted,
  // The tracker's own map (no mapper): observing keyframes. No culling or triangulation feeds it, and
  // the weighted count inserted more keyframes for a worse MH01 (4.14 against 3.79 mm).
  keyframes,
};

// Minimum observations for a reference point to count (ORB-SLAM2: 3, or 2 while the map is tiny).
int reference_min_observations(int keyframes_in_map);
int count_reference_points(const Keyframe& reference, const Map& map, int min_observations, ObservationCount unit);
// Of count_reference_points' points, those whose keyframe feature is near a clip edge.
int count_reference_points_near_clip(const Keyframe& reference, const Map& map, int min_observations,
                                     ObservationCount unit);
// The frame's matched map points whose feature is near a clip edge.
int count_tracked_near_clip(const Frame& frame);

// Whether a keyframe (not culled) made at least options.revisit_min_age_s before the frame is within
// options.revisit_max_distance_baselines baselines and options.revisit_max_angle_deg of its pose, or
// within that distance at any angle while options.revisit_min_old_inlier_share of the frame's tracked
// inliers are old points (old_inlier_share()).
bool revisit_covered(const Frame& frame, const Map& map, const PinholeStereo& camera, const TrackerOptions& options);

// The share of the frame's tracked inliers whose point's reference keyframe was made at least
// `min_age_s` before the frame (0 without inliers).
double old_inlier_share(const Frame& frame, const Map& map, double min_age_s);

KeyframeDecision decide_keyframe(const Frame& frame, const PinholeStereo& camera, const KeyframeDecisionInput& input,
                                 const TrackerOptions& options);

}  // namespace heslam

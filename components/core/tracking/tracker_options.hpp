// Tunables of the stereo frame tracker, with ORB-SLAM2's values as defaults and why each is what it is.
//
// The settings file sets only close_depth_baselines (ThDepth), max_frames_between_keyframes
// (Camera.fps), stationary_test_chi2, rotation_only_test_chi2 and ransac_seed (Tracker.*;
// tracker_settings.hpp). Every other field is a constant: ORB-SLAM2's, or measured here as its
// comment says; tests and benchmarks may set it in code.
#pragma once

#include <cstdint>

namespace heslam {

struct TrackerOptions {
  // --- initialization ---
  // ORB-SLAM2 stereo (Tracking::StereoInitialization) starts the map on the first frame with more than
  // 500 keypoints (N > 500), whatever its stereo count. EuRoC frames of 1200 ORB features give 350-450
  // stereo matches, so requiring 500 *stereo* points would never start; a floor on stereo points
  // keeps a textureless or black first frame from seeding a map of a handful of points.
  int min_features_to_initialize = 500;
  int min_stereo_points_to_initialize = 150;

  // --- the atlas (docs/frontend.md, Atlas) ---
  // Lost, and relocalization in every map failed, for this long (frame stamps, never wall clock, so a
  // lockstep run repeats): the frame starts a new map, initialized from it alone as the first frame is.
  // 0: never (wait for relocalization, as before the atlas). The frontend sets it from
  // atlas.new_map_after_s (default 1 s); this default keeps the tracker's own tests as they were.
  std::int64_t new_map_after_ns = 0;

  // --- depth classes ---
  // Stereo points closer than this many baselines are "close" (reliable depth): ORB-SLAM2 ThDepth = 35.
  double close_depth_baselines = 35.0;

  // --- descriptor matching ---
  int descriptor_threshold_high = 100;  // TH_HIGH: accept a projection match at most this far
  int descriptor_threshold_low = 50;    // TH_LOW: brute-force / relocalization matches
  bool check_orientation = true;        // keep matches in the 3 dominant rotation-histogram bins

  // --- motion model search (ORB-SLAM2 TrackWithMotionModel, stereo) ---
  float motion_search_radius_px = 7.f;  // times the keypoint's scale; doubled once if too few matches
  int min_motion_matches = 20;          // fewer: widen the window, then fall back to the reference keyframe

  // --- reference keyframe search (no bag of words yet: guided projection, then brute force) ---
  float reference_search_radius_px = 25.f;  // wide: the motion model failed, the pose guess is poor
  float reference_ratio = 0.7f;             // nearest / second nearest (ORB-SLAM2 uses 0.7 with BoW)
  int min_reference_matches = 15;

  // After pose optimization in motion-model / reference tracking: at least this many inlier map points.
  int min_pose_inliers = 10;

  // --- local map search (ORB-SLAM2 SearchLocalPoints) ---
  float local_search_radius_px = 3.f;  // stereo/RGB-D value in ORB-SLAM2 (th = 3)
  float local_search_radius_relocalized_px = 5.f;
  float local_ratio = 0.8f;                    // best / second best, applied when both are on one level
  float min_view_cosine = 0.5f;                // the point was never seen from more than 60 degrees off
  int local_map_max_keyframes = 80;            // ORB-SLAM2 caps the local keyframe set at 80
  int local_map_neighbours_per_keyframe = 10;  // best covisible neighbours added per local keyframe
  int min_local_map_inliers = 30;              // fewer: tracking is lost
  int min_local_map_inliers_after_relocalization = 50;

  // --- a frame after a gap (issue 41; docs/frontend.md "After a gap"; not in ORB-SLAM2) ---
  // A frame whose seq is more than one past the last frame's (frames the tracker never saw: missed or
  // shed in real time) may start from a prediction that is far off; a wrong start can converge to a
  // wrong pose that still gathers the 30 local-map inliers of min_local_map_inliers (MH01 with 10
  // frames dropped: 40-51 inliers 59-153 mm off, where the right pose gathers 238-318). Its pose is
  // doubtful when it has fewer than min_local_map_inliers_after_gap inliers or fewer than
  // gap_doubt_ratio times the last tracked frame's; then every other start is tried (the one-frame
  // motion model, the last pose, relocalization by bag of words) and the frame keeps the pose with most
  // inliers only if it has min_local_map_inliers_after_gap of them and no pose further than
  // gap_agreement_baselines baselines or gap_agreement_deg from it has gap_ambiguity_ratio of its
  // inliers; otherwise the frame is lost (refused). A frame checked that way makes no keyframe.
  int min_local_map_inliers_after_gap = 50;  // as after a relocalization
  double gap_doubt_ratio = 0.5;
  double gap_ambiguity_ratio = 0.5;
  double gap_agreement_baselines = 0.25;
  double gap_agreement_deg = 2.0;

  // --- motion-only bundle adjustment ---
  int pose_optimization_rounds = 4;       // outlier reclassification rounds
  int pose_optimization_iterations = 10;  // Levenberg-Marquardt iterations per round
  double disparity_sigma_ratio = 0.5;     // disparity sigma / keypoint sigma in motion-only BA (motion_only_ba.hpp)
  // --- stationary test (stationary_test.hpp; not in ORB-SLAM2) ---
  // A frame whose observations cannot tell its optimized pose from the last pose keeps the last pose
  // (chi2 increase below this; chi-square 6 dof, 16.81 = 99 %), so a still camera is estimated still.
  // 0 disables the test.
  double stationary_test_chi2 = 16.81;
  // Else, a frame whose observations cannot tell it from a rotation about the last camera centre
  // keeps that centre (chi-square 3 dof, 11.34 = 99 %): a camera turning in place does not pick up
  // translation noise from the rotation. 0 disables this second test.
  double rotation_only_test_chi2 = 11.34;

  // --- keyframe decision (ORB-SLAM2 NeedNewKeyFrame, stereo) ---
  int max_frames_between_keyframes = 20;  // = camera fps in ORB-SLAM2: at least one keyframe a second
  int min_frames_between_keyframes = 0;
  int close_tracked_needed = 100;   // fewer close points tracked ...
  int close_untracked_enough = 70;  // ... and this many close ones could be added: insert
  // An untracked close feature whose stereo match is near a clip edge (StereoFeatures::near_clip, set
  // only in pairs exposed apart) counts this much towards close_untracked_enough; the tracked side is
  // unchanged. Such features are 80-93 % of a clipped pair's stereo points and keep the rule firing
  // (MH01 left x1 / right x4.1: 16 keyframes against 10 at equal exposure); 0.9 brings that to 14 and
  // changed no run for the worse (0.85-0.95 alike; 0.75 and below hurt x0.5/x1.5; 0: too few
  // keyframes, frames lost). Equally exposed pairs carry no marks. docs/benchmarks.md at 5c1f792, gain4.
  double close_untracked_near_clip_weight = 0.9;
  float reference_ratio_stereo = 0.75f;
  // In the reference-ratio rule (tracked < reference_ratio_stereo x the reference keyframe's points),
  // points whose keyframe / frame feature is near a clip edge (StereoFeatures::near_clip, pairs exposed
  // apart only) count this much on both sides. Such points are found again less often than the others
  // (a clip contour slides with the view), so at 1 the rule fires every frame or two on heavily clipped
  // pairs in the full system. Equally exposed pairs carry no marks. docs/benchmarks.md at 5c1f792, gain5.
  double reference_near_clip_weight = 1.0;
  float reference_ratio_single_keyframe = 0.4f;
  int min_keyframe_inliers = 15;
  // Revisits (issue 41; not in ORB-SLAM2): a frame whose camera is within revisit_max_distance_baselines
  // baselines and revisit_max_angle_deg (optical axes) of a keyframe made at least revisit_min_age_s
  // earlier (a place mapped before, not the keyframes just made) makes no keyframe, unless its tracking
  // is weak (fewer than a quarter of the reference keyframe's points): laps over mapped places then
  // re-use the map instead of growing it with time. revisit_min_age_s 0: off.
  double revisit_min_age_s = 10.0;
  double revisit_max_distance_baselines = 3.0;
  double revisit_max_angle_deg = 15.0;
  // A frame near such a keyframe (within the distance) but looking further away is covered too when at
  // least this share of its tracked inliers are old points (their reference keyframe made at least
  // revisit_min_age_s before the frame): it sees nothing the map lacks. room_laps' lap-2 keyframes looked
  // 15-25 degrees off lap 1's and tracked 400-500 inliers, 78-100 % of them lap 1's points. Lockstep
  // (docs/benchmarks.md, Long runs): 0.99 holds lap 2 to +8.8 % keyframes (real time: 0 keyframes in
  // laps 2-4) at `room` 5.794 mm (5.667 without); 0.75-0.97 to +2.5 % at 5.954 mm. 0: the angle alone.
  double revisit_min_old_inlier_share = 0.99;
  // Points created for a new keyframe: all close untracked ones, then far ones until this many in all.
  int new_keyframe_min_points = 100;

  // False: localization only (ORB-SLAM3's localization mode): no keyframe and no map point is ever
  // created, not even the first keyframe of an empty map; frames are tracked against the map the
  // tracker holds (a loaded one) and relocalized in it when lost.
  bool create_keyframes = true;

  // --- relocalization ---
  int relocalization_keyframes = 8;    // most recent keyframes tried, newest first
  float relocalization_ratio = 0.75f;  // ORB-SLAM2 relocalization BoW ratio
  int min_relocalization_matches = 15;
  int min_relocalization_inliers = 50;  // ORB-SLAM2: 50 after pose optimization
  std::uint64_t ransac_seed = 0x5eed;   // PnP RANSAC: same seed + same frame = same pose

  // --- map maintenance ---
  // True when no local mapper runs: the tracker itself adds observations of tracked points to each new
  // keyframe, updates point normals / descriptors and the covisibility graph. False when a mapper owns
  // that state and the frontend mirrors it.
  bool maintain_map = true;
  // With maintain_map: a point's position becomes the inverse-variance weighted mean of its stereo
  // observations (a local mapper's BA does better; this is the tracker-alone stand-in).
  bool fuse_stereo_observations = true;
  // Lockstep runs (and a tracker alone) treat the mapper as idle; real time reports it per frame.
  bool assume_mapper_idle = true;
  // Creator tag for keyframe and point ids (map.hpp).
  std::uint8_t id_tag = 1;
  // The first map's id; maps started after a loss count up from it (ids.hpp: agent a's maps are
  // first_map_id(a) + 0, 1, 2, ...), so several agents number their maps without coordination.
  std::uint32_t first_map_id = 0;

  bool operator==(const TrackerOptions&) const = default;
};

}  // namespace heslam

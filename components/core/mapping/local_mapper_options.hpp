// Tunables of the local mapper, one struct per stage, with ORB-SLAM2's values as documented defaults.
#pragma once

#include <functional>

namespace heslam {

struct CovisibilityOptions {
  int min_shared_points = 15;  // ORB-SLAM2: an edge needs 15 shared points (else keep only the best)
};

struct PointCullingOptions {
  float min_found_ratio = 0.25f;       // found / visible below this: the point is rarely matched when seen
  int keyframes_before_obs_check = 2;  // keyframes after creation before the observation count is checked
  int min_observations = 3;            // stereo: points seen by fewer keyframes by then are culled
  int keyframes_until_mature = 3;      // after this many keyframes a point leaves the recent list
};

struct TriangulationOptions {
  int neighbours = 10;               // best covisible keyframes searched (ORB-SLAM2 stereo: 10)
  int max_descriptor_distance = 50;  // TH_LOW
  float epipolar_chi2 = 3.84f;       // 1-dof chi2 at 95 %: keypoint distance to the epipolar line
  double min_parallax_cos = 0.9998;  // rays closer than ~1.1 deg carry no depth information
  float mono_chi2 = 5.991f;          // 2-dof chi2 at 95 %
  float stereo_chi2 = 7.815f;        // 3-dof chi2 at 95 %
  float scale_ratio_factor = 1.5f;   // distance ratio may exceed the octave ratio by this x scale factor
  bool check_orientation = true;     // rotation-consistency histogram as in ORB-SLAM2
};

struct FusionOptions {
  int neighbours = 10;               // first-order neighbours (ORB-SLAM2 stereo: 10)
  int second_neighbours = 5;         // best neighbours of each neighbour
  float radius_factor = 3.f;         // search radius in pixels at level 0, scaled by the level
  int max_descriptor_distance = 50;  // TH_LOW
  float mono_chi2 = 5.991f;
  float stereo_chi2 = 7.815f;
  double min_view_cos = 0.5;  // viewing direction within 60 deg of the mean
};

struct LocalBundleAdjustmentOptions {
  int first_pass_iterations = 5;  // ORB-SLAM2: 5 robust iterations, outlier removal, then 10
  int second_pass_iterations = 10;
  float mono_chi2 = 5.991f;
  float stereo_chi2 = 7.815f;
  // Disparity sigma / keypoint sigma of stereo observations; the tracker's motion-only BA uses the
  // same model (tracker.disparity_sigma_ratio), docs/tracking.md has the measurements.
  double disparity_sigma_ratio = 0.5;
  int num_threads = 1;  // no effect: the local BA's own solver is single-threaded (configs still set it)
  // Real-time mode: asked after every solver iteration; true stops the BA there (a new keyframe is
  // waiting, as ORB-SLAM2's abort flag). The state reached so far is kept and outliers are still
  // removed; the second pass is skipped. Empty = never stop (lockstep: always complete).
  std::function<bool()> stop_requested;
};

struct KeyframeCullingOptions {
  double redundant_ratio = 0.9;         // a keyframe is redundant when 90 % of its points are seen elsewhere
  int min_other_observers = 3;          // ... by at least this many other keyframes
  double close_depth_baselines = 35.0;  // stereo: only points closer than 35 baselines count
};

struct LocalMapperOptions {
  CovisibilityOptions covisibility;
  PointCullingOptions point_culling;
  TriangulationOptions triangulation;
  FusionOptions fusion;
  LocalBundleAdjustmentOptions bundle_adjustment;
  KeyframeCullingOptions keyframe_culling;
  bool enable_triangulation = true;
  bool enable_fusion = true;
  bool enable_bundle_adjustment = true;
  bool enable_keyframe_culling = true;
};

}  // namespace heslam

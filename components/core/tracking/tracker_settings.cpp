// ORB-SLAM2 settings keys -> TrackerOptions (see tracker_settings.hpp).
#include "components/core/tracking/tracker_settings.hpp"

#include <climits>
#include <cmath>

#include "components/core/image/yaml_option.hpp"

namespace heslam {
namespace {

// Upper bounds that only catch typos (a value beyond them is certainly a mistake).
constexpr int kMaxCount = 100000;
constexpr double kMaxPixels = 1000.0;

void read_int(const cv::FileNode& root, const std::string& source, const char* key, int& value, int min = 0,
              int max = kMaxCount) {
  yaml_option::read(root, key, source, value);
  if (value < min || value > max) {
    yaml_option::fail(source, key, "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
}

template <typename Number>
void read_number(const cv::FileNode& root, const std::string& source, const char* key, Number& value, double min,
                 double max) {
  double read = value;
  yaml_option::read(root, key, source, read);
  if (!(read >= min && read <= max)) {
    yaml_option::fail(source, key, "a number in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  value = static_cast<Number>(read);
}

}  // namespace

void read_tracker_settings(const cv::FileNode& root, const std::string& source, TrackerOptions& t) {
  double fps = 0.0;
  yaml_option::read(root, "Camera.fps", source, fps);
  if (yaml_option::present(root, "Camera.fps")) {
    if (!(fps > 0.0) || fps > 10000.0) yaml_option::fail(source, "Camera.fps", "a frame rate in (0, 10000]");
    t.max_frames_between_keyframes = std::max(1, static_cast<int>(std::lround(fps)));
  }
  read_number(root, source, "ThDepth", t.close_depth_baselines, 1.0, 1000.0);
  // ORB-SLAM3 names the same threshold Stereo.ThDepth.
  if (yaml_option::present(root, "Stereo.ThDepth") && yaml_option::present(root, "ThDepth")) {
    yaml_option::fail(source, "Stereo.ThDepth", "one of ThDepth (ORB-SLAM2) and Stereo.ThDepth (ORB-SLAM3), not both");
  }
  read_number(root, source, "Stereo.ThDepth", t.close_depth_baselines, 1.0, 1000.0);

  read_int(root, source, "Tracker.minFeaturesToInitialize", t.min_features_to_initialize);
  read_int(root, source, "Tracker.minStereoPointsToInitialize", t.min_stereo_points_to_initialize);
  read_int(root, source, "Tracker.descriptorThresholdHigh", t.descriptor_threshold_high, 0, 256);
  read_int(root, source, "Tracker.descriptorThresholdLow", t.descriptor_threshold_low, 0, 256);
  yaml_option::read(root, "Tracker.checkOrientation", source, t.check_orientation);
  read_number(root, source, "Tracker.motionSearchRadius", t.motion_search_radius_px, 0.5, kMaxPixels);
  read_int(root, source, "Tracker.minMotionMatches", t.min_motion_matches);
  read_number(root, source, "Tracker.referenceSearchRadius", t.reference_search_radius_px, 0.5, kMaxPixels);
  read_number(root, source, "Tracker.referenceRatio", t.reference_ratio, 0.0, 1.0);
  read_int(root, source, "Tracker.minReferenceMatches", t.min_reference_matches);
  read_int(root, source, "Tracker.minPoseInliers", t.min_pose_inliers);
  read_number(root, source, "Tracker.localSearchRadius", t.local_search_radius_px, 0.5, kMaxPixels);
  read_number(root, source, "Tracker.localSearchRadiusRelocalized", t.local_search_radius_relocalized_px, 0.5,
              kMaxPixels);
  read_number(root, source, "Tracker.localRatio", t.local_ratio, 0.0, 1.0);
  read_number(root, source, "Tracker.minViewCosine", t.min_view_cosine, -1.0, 1.0);
  read_int(root, source, "Tracker.localMapMaxKeyframes", t.local_map_max_keyframes, 1);
  read_int(root, source, "Tracker.localMapNeighboursPerKeyframe", t.local_map_neighbours_per_keyframe);
  read_int(root, source, "Tracker.minLocalMapInliers", t.min_local_map_inliers);
  read_int(root, source, "Tracker.minLocalMapInliersAfterRelocalization", t.min_local_map_inliers_after_relocalization);
  read_int(root, source, "Tracker.poseOptimizationRounds", t.pose_optimization_rounds, 1, 100);
  read_int(root, source, "Tracker.poseOptimizationIterations", t.pose_optimization_iterations, 1, 1000);
  read_number(root, source, "Tracker.disparitySigmaRatio", t.disparity_sigma_ratio, 0.01, 100.0);
  read_number(root, source, "Tracker.stationaryTestChi2", t.stationary_test_chi2, 0.0, 1e6);
  read_number(root, source, "Tracker.rotationOnlyTestChi2", t.rotation_only_test_chi2, 0.0, 1e6);
  read_int(root, source, "Tracker.minFramesBetweenKeyframes", t.min_frames_between_keyframes);
  read_int(root, source, "Tracker.closeTrackedNeeded", t.close_tracked_needed);
  read_int(root, source, "Tracker.closeUntrackedEnough", t.close_untracked_enough);
  read_number(root, source, "Tracker.closeUntrackedNearClipWeight", t.close_untracked_near_clip_weight, 0.0, 1.0);
  read_number(root, source, "Tracker.referenceRatioStereo", t.reference_ratio_stereo, 0.0, 1.0);
  read_number(root, source, "Tracker.referenceNearClipWeight", t.reference_near_clip_weight, 0.0, 1.0);
  read_number(root, source, "Tracker.referenceRatioSingleKeyframe", t.reference_ratio_single_keyframe, 0.0, 1.0);
  read_int(root, source, "Tracker.minKeyframeInliers", t.min_keyframe_inliers);
  read_int(root, source, "Tracker.newKeyframeMinPoints", t.new_keyframe_min_points);
  read_int(root, source, "Tracker.relocalizationKeyframes", t.relocalization_keyframes, 1);
  read_number(root, source, "Tracker.relocalizationRatio", t.relocalization_ratio, 0.0, 1.0);
  read_int(root, source, "Tracker.minRelocalizationMatches", t.min_relocalization_matches);
  read_int(root, source, "Tracker.minRelocalizationInliers", t.min_relocalization_inliers);
  int seed = static_cast<int>(t.ransac_seed);
  read_int(root, source, "Tracker.ransacSeed", seed, 0, INT_MAX);
  t.ransac_seed = static_cast<std::uint64_t>(seed);
}

}  // namespace heslam

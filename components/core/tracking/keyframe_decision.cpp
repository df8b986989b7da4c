// ORB-SLAM2's stereo keyframe rules.
#include "components/core/tracking/keyframe_decision.hpp"

#include <cmath>
#include <cstdint>

namespace heslam {
namespace {

// Stereo: insert also when tracking is thin, below this fraction of the reference keyframe's points.
constexpr float kWeakTrackingRatio = 0.25f;
constexpr int kTinyMapKeyframes = 2;
constexpr double kPi = 3.14159265358979323846;

// A reference point's observations in the given unit.
int observations(const Map& map, const MapPoint& point, ObservationCount unit) {
  return unit == ObservationCount::weighted ? observation_weight(map, point)
                                            : static_cast<int>(point.observations.size());
}

}  // namespace

int reference_min_observations(int keyframes_in_map) { return keyframes_in_map <= kTinyMapKeyframes ? 2 : 3; }

int count_reference_points(const Keyframe& reference, const Map& map, int min_observations, ObservationCount unit) {
  int count = 0;
  for (PointId id : reference.point_ids) {
    const MapPoint* point = map.point(id);
    if (point != nullptr && !point->culled && observations(map, *point, unit) >= min_observations) ++count;
  }
  return count;
}

int count_reference_points_near_clip(const Keyframe& reference, const Map& map, int min_observations,
                                     ObservationCount unit) {
  int count = 0;
  for (std::size_t i = 0; i < reference.point_ids.size(); ++i) {
    if (!reference.features.stereo_near_clip(i)) continue;
    const MapPoint* point = map.point(reference.point_ids[i]);
    if (point != nullptr && !point->culled && observations(map, *point, unit) >= min_observations) ++count;
  }
  return count;
}

int count_tracked_near_clip(const Frame& frame) {
  int count = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.point_ids[i] != kNoId && !frame.outlier[i] && frame.features.stereo_near_clip(i)) ++count;
  }
  return count;
}

bool revisit_covered(const Frame& frame, const Map& map, const PinholeStereo& camera, const TrackerOptions& options) {
  if (options.revisit_min_age_s <= 0.0) return false;
  const auto newest_ns = frame.stamp_ns - static_cast<std::int64_t>(options.revisit_min_age_s * 1e9);
  const double max_distance_m = options.revisit_max_distance_baselines * camera.baseline_m;
  const double min_cos = std::cos(options.revisit_max_angle_deg * kPi / 180.0);
  const Eigen::Vector3d axis = frame.T_wc.linear().col(2);
  bool near = false;
  for (const auto& [id, keyframe] : map.keyframes) {
    if (keyframe.culled || keyframe.stamp_ns > newest_ns) continue;
    if ((keyframe.T_wc.translation() - frame.T_wc.translation()).norm() > max_distance_m) continue;
    if (keyframe.T_wc.linear().col(2).dot(axis) >= min_cos) return true;
    near = true;
  }
  const double share = options.revisit_min_old_inlier_share;
  return near && share > 0.0 && share <= 1.0 && old_inlier_share(frame, map, options.revisit_min_age_s) >= share;
}

double old_inlier_share(const Frame& frame, const Map& map, double min_age_s) {
  const auto newest_ns = frame.stamp_ns - static_cast<std::int64_t>(min_age_s * 1e9);
  int inliers = 0;
  int old = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.point_ids[i] == kNoId || frame.outlier[i]) continue;
    ++inliers;
    const MapPoint* point = map.point(frame.point_ids[i]);
    const Keyframe* reference = point == nullptr ? nullptr : map.keyframe(point->reference_kf);
    if (reference != nullptr && reference->stamp_ns <= newest_ns) ++old;
  }
  return inliers > 0 ? static_cast<double>(old) / inliers : 0.0;
}

KeyframeDecision decide_keyframe(const Frame& frame, const PinholeStereo& camera, const KeyframeDecisionInput& input,
                                 const TrackerOptions& options) {
  KeyframeDecision decision;
  // Just after a relocalization the pose is fragile: no keyframe until a second has passed.
  if (input.frames_since_relocalization < options.max_frames_between_keyframes &&
      input.keyframes_in_map > options.max_frames_between_keyframes) {
    return decision;
  }
  const double close_depth_m = options.close_depth_baselines * camera.baseline_m;
  double untracked_weight = 0.0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const float depth = frame.features.depth_m[i];
    if (depth <= 0.f || depth >= close_depth_m) continue;
    if (frame.point_ids[i] != kNoId && !frame.outlier[i]) {
      ++decision.tracked_close;
    } else {
      ++decision.untracked_close;
      untracked_weight += frame.features.stereo_near_clip(i) ? options.close_untracked_near_clip_weight : 1.0;
    }
  }
  const bool need_close =
      decision.tracked_close < options.close_tracked_needed && untracked_weight > options.close_untracked_enough;
  const float ratio =
      input.keyframes_in_map < 2 ? options.reference_ratio_single_keyframe : options.reference_ratio_stereo;
  const double near_clip_discount = 1.0 - options.reference_near_clip_weight;
  const auto reference =
      static_cast<float>(input.reference_tracked_points - near_clip_discount * input.reference_points_near_clip);
  const auto tracked = static_cast<float>(input.tracked_inliers - near_clip_discount * input.tracked_inliers_near_clip);

  const bool c1a = input.frames_since_keyframe >= options.max_frames_between_keyframes;
  const bool c1b = input.frames_since_keyframe >= options.min_frames_between_keyframes && input.mapper_idle;
  const bool c1c = tracked < reference * kWeakTrackingRatio || need_close;
  const bool c2 = (tracked < reference * ratio || need_close) && input.tracked_inliers > options.min_keyframe_inliers;
  // A busy mapper would be interrupted in ORB-SLAM2; stereo still inserts (its queue is short), so the
  // mapper state only gates c1b here.
  decision.insert = (c1a || c1b || c1c) && c2;
  // A place mapped before: the map has its keyframes; only weak tracking still asks for one.
  if (decision.insert && input.revisit_covered && !(tracked < reference * kWeakTrackingRatio)) {
    decision.insert = false;
    decision.covered = true;
  }
  return decision;
}

}  // namespace heslam

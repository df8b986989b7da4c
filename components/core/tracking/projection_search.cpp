// Projection and brute-force searches between map points and the current frame's keypoints.
#include "components/core/tracking/projection_search.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "components/core/tracking/rotation_histogram.hpp"

namespace heslam {
namespace {

// Scale-range check tolerance: ORB-SLAM2 accepts distances 20 % outside a point's invariance range.
constexpr float kMinDistanceSlack = 0.8f;
constexpr float kMaxDistanceSlack = 1.2f;
// Viewing almost head-on (within ~3.6 degrees of the mean view): a tighter window suffices.
constexpr float kHeadOnCosine = 0.998f;
constexpr float kHeadOnRadiusFactor = 2.5f;
constexpr float kObliqueRadiusFactor = 4.0f;

// Pyramid level at which a point at this distance should be detected (ORB-SLAM2 PredictScale).
int predict_level(const MapPoint& point, float distance_m, const ScalePyramid& pyramid) {
  const float ratio = point.max_distance_m / distance_m;
  int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(pyramid.scale_factor)));
  return std::clamp(level, 0, pyramid.levels - 1);
}

// A keypoint is free when nothing is matched to it yet.
bool is_free(const Frame& frame, int index) { return frame.point_ids[static_cast<std::size_t>(index)] == kNoId; }

void apply_rotation_check(Frame& current, const RotationHistogram& histogram, int& matches) {
  for (int index : histogram.rejected()) {
    current.point_ids[static_cast<std::size_t>(index)] = kNoId;
    --matches;
  }
}

}  // namespace

int search_from_last_frame(Frame& current, const Frame& last, const Map& map, const PinholeStereo& camera,
                           float radius_px, const TrackerOptions& options) {
  const Pose3 T_cw = current.T_cw();
  // Motion along the optical axis since the last frame: moving forward, points look larger and are
  // detected at the same or a coarser level; moving backward, the same or a finer one.
  const Eigen::Vector3d t_lc = (last.T_cw() * current.T_wc).translation();
  const bool forward = t_lc.z() > camera.baseline_m;
  const bool backward = -t_lc.z() > camera.baseline_m;
  const ScalePyramid& pyramid = current.features.pyramid;

  RotationHistogram histogram;
  int matches = 0;
  std::vector<int> candidates;  // reused by every point's query
  for (std::size_t i = 0; i < last.size(); ++i) {
    const PointId id = last.point_ids[i];
    if (id == kNoId || last.outlier[i]) continue;
    const MapPoint* point = map.point(id);
    if (point == nullptr || point->culled) continue;
    const Eigen::Vector3d p_c = T_cw * point->p_w;
    if (p_c.z() <= 0.0) continue;
    const Eigen::Vector2d uv = camera.project(p_c);
    if (!camera.in_image(uv.x(), uv.y())) continue;
    const double ur_predicted = uv.x() - camera.bf() / p_c.z();

    const int last_octave = last.features.keypoints[i].octave;
    const float radius = radius_px * pyramid.scale[static_cast<std::size_t>(last_octave)];
    if (forward) {
      current.grid.in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius, last_octave, -1, candidates);
    } else if (backward) {
      current.grid.in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius, 0, last_octave, candidates);
    } else {
      current.grid.in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius, std::max(0, last_octave - 1),
                           last_octave + 1, candidates);
    }
    int best_distance = std::numeric_limits<int>::max();
    int best_index = -1;
    for (int index : candidates) {
      if (!is_free(current, index)) continue;
      const float ur = current.features.u_right_px[static_cast<std::size_t>(index)];
      if (ur > 0.f && std::abs(ur_predicted - ur) > radius) continue;
      const int distance =
          hamming_distance(point->descriptor, current.features.descriptors[static_cast<std::size_t>(index)]);
      if (distance < best_distance) {
        best_distance = distance;
        best_index = index;
      }
    }
    if (best_index < 0 || best_distance > options.descriptor_threshold_high) continue;
    current.point_ids[static_cast<std::size_t>(best_index)] = id;
    ++matches;
    if (options.check_orientation) {
      histogram.add(last.features.keypoints[i].angle_deg,
                    current.features.keypoints[static_cast<std::size_t>(best_index)].angle_deg, best_index);
    }
  }
  if (options.check_orientation) apply_rotation_check(current, histogram, matches);
  return matches;
}

int search_local_points(Frame& current, const std::vector<PointId>& local_points, Map& map, const PinholeStereo& camera,
                        float radius_px, const TrackerOptions& options) {
  const Pose3 T_cw = current.T_cw();
  const Eigen::Vector3d camera_center_w = current.T_wc.translation();
  const ScalePyramid& pyramid = current.features.pyramid;

  // Points already matched in this frame are skipped (they were counted visible by the caller).
  // Only the matched keypoints' ids: no local point is kNoId.
  std::vector<PointId> matched;
  matched.reserve(current.point_ids.size());
  for (PointId id : current.point_ids) {
    if (id != kNoId) matched.push_back(id);
  }
  std::sort(matched.begin(), matched.end());

  int matches = 0;
  std::vector<int> candidates;  // reused by every point's query
  for (PointId id : local_points) {
    if (std::binary_search(matched.begin(), matched.end(), id)) continue;
    MapPoint* point = map.point(id);
    if (point == nullptr || point->culled) continue;

    // Frustum and invariance checks (ORB-SLAM2 Frame::isInFrustum).
    const Eigen::Vector3d p_c = T_cw * point->p_w;
    if (p_c.z() <= 0.0) continue;
    const Eigen::Vector2d uv = camera.project(p_c);
    if (!camera.in_image(uv.x(), uv.y())) continue;
    const Eigen::Vector3d ray_w = point->p_w - camera_center_w;
    const float distance = static_cast<float>(ray_w.norm());
    if (distance < kMinDistanceSlack * point->min_distance_m || distance > kMaxDistanceSlack * point->max_distance_m) {
      continue;
    }
    const float view_cosine = static_cast<float>(ray_w.dot(point->normal) / distance);
    if (view_cosine < options.min_view_cosine) continue;
    ++point->visible;

    const int level = predict_level(*point, distance, pyramid);
    const float radius = radius_px * (view_cosine > kHeadOnCosine ? kHeadOnRadiusFactor : kObliqueRadiusFactor) *
                         pyramid.scale[static_cast<std::size_t>(level)];
    const double ur_predicted = uv.x() - camera.bf() / p_c.z();
    current.grid.in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius, level - 1, level, candidates);

    int best_distance = std::numeric_limits<int>::max();
    int second_distance = std::numeric_limits<int>::max();
    int best_level = -1;
    int second_level = -1;
    int best_index = -1;
    for (int index : candidates) {
      if (!is_free(current, index)) continue;
      const std::size_t k = static_cast<std::size_t>(index);
      const float ur = current.features.u_right_px[k];
      if (ur > 0.f && std::abs(ur_predicted - ur) > radius) continue;
      const int d = hamming_distance(point->descriptor, current.features.descriptors[k]);
      if (d < best_distance) {
        second_distance = best_distance;
        second_level = best_level;
        best_distance = d;
        best_level = current.features.keypoints[k].octave;
        best_index = index;
      } else if (d < second_distance) {
        second_distance = d;
        second_level = current.features.keypoints[k].octave;
      }
    }
    if (best_index < 0 || best_distance > options.descriptor_threshold_high) continue;
    if (best_level == second_level && best_distance > options.local_ratio * second_distance) continue;
    current.point_ids[static_cast<std::size_t>(best_index)] = id;
    ++matches;
  }
  return matches;
}

int search_keyframe_by_projection(Frame& current, const Keyframe& keyframe, const Map& map, const PinholeStereo& camera,
                                  float radius_px, float ratio, const TrackerOptions& options) {
  const Pose3 T_cw = current.T_cw();
  const ScalePyramid& pyramid = current.features.pyramid;
  RotationHistogram histogram;
  int matches = 0;
  std::vector<int> candidates;  // reused by every point's query
  for (std::size_t i = 0; i < keyframe.point_ids.size(); ++i) {
    const PointId id = keyframe.point_ids[i];
    if (id == kNoId) continue;
    const MapPoint* point = map.point(id);
    if (point == nullptr || point->culled) continue;
    const Eigen::Vector3d p_c = T_cw * point->p_w;
    if (p_c.z() <= 0.0) continue;
    const Eigen::Vector2d uv = camera.project(p_c);
    if (!camera.in_image(uv.x(), uv.y())) continue;
    const int octave = keyframe.features.keypoints[i].octave;
    const float radius = radius_px * pyramid.scale[static_cast<std::size_t>(octave)];
    current.grid.in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius, std::max(0, octave - 2),
                         octave + 2, candidates);
    int best_distance = std::numeric_limits<int>::max();
    int second_distance = std::numeric_limits<int>::max();
    int best_index = -1;
    for (int index : candidates) {
      if (!is_free(current, index)) continue;
      const int d = hamming_distance(keyframe.features.descriptors[i],
                                     current.features.descriptors[static_cast<std::size_t>(index)]);
      if (d < best_distance) {
        second_distance = best_distance;
        best_distance = d;
        best_index = index;
      } else if (d < second_distance) {
        second_distance = d;
      }
    }
    if (best_index < 0 || best_distance > options.descriptor_threshold_high) continue;
    if (static_cast<float>(best_distance) >= ratio * static_cast<float>(second_distance)) continue;
    current.point_ids[static_cast<std::size_t>(best_index)] = id;
    ++matches;
    if (options.check_orientation) {
      histogram.add(keyframe.features.keypoints[i].angle_deg,
                    current.features.keypoints[static_cast<std::size_t>(best_index)].angle_deg, best_index);
    }
  }
  if (options.check_orientation) apply_rotation_check(current, histogram, matches);
  return matches;
}

int search_keyframe_brute_force(Frame& current, const Keyframe& keyframe, const Map& map, float ratio,
                                const TrackerOptions& options) {
  RotationHistogram histogram;
  // Best keyframe point for each keypoint, so two points never claim one keypoint.
  std::vector<int> best_distance(current.size(), std::numeric_limits<int>::max());
  std::vector<int> best_source(current.size(), -1);
  for (std::size_t i = 0; i < keyframe.point_ids.size(); ++i) {
    const PointId id = keyframe.point_ids[i];
    if (id == kNoId) continue;
    const MapPoint* point = map.point(id);
    if (point == nullptr || point->culled) continue;
    int best = std::numeric_limits<int>::max();
    int second = std::numeric_limits<int>::max();
    int best_index = -1;
    for (std::size_t k = 0; k < current.size(); ++k) {
      if (current.point_ids[k] != kNoId) continue;
      const int d = hamming_distance(keyframe.features.descriptors[i], current.features.descriptors[k]);
      if (d < best) {
        second = best;
        best = d;
        best_index = static_cast<int>(k);
      } else if (d < second) {
        second = d;
      }
    }
    if (best_index < 0 || best > options.descriptor_threshold_low) continue;
    if (static_cast<float>(best) >= ratio * static_cast<float>(second)) continue;
    const std::size_t k = static_cast<std::size_t>(best_index);
    if (best < best_distance[k]) {
      best_distance[k] = best;
      best_source[k] = static_cast<int>(i);
    }
  }
  int matches = 0;
  for (std::size_t k = 0; k < current.size(); ++k) {
    if (best_source[k] < 0) continue;
    const std::size_t i = static_cast<std::size_t>(best_source[k]);
    current.point_ids[k] = keyframe.point_ids[i];
    ++matches;
    if (options.check_orientation) {
      histogram.add(keyframe.features.keypoints[i].angle_deg, current.features.keypoints[k].angle_deg,
                    static_cast<int>(k));
    }
  }
  if (options.check_orientation) apply_rotation_check(current, histogram, matches);
  return matches;
}

}  // namespace heslam

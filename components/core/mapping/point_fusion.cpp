// Fusion of duplicated map points between a keyframe and its neighbours.
#include "components/core/mapping/point_fusion.hpp"

#include <algorithm>
#include <set>

#include "components/core/mapping/covisibility.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"

namespace heslam {
namespace {

// ORB-SLAM2 accepts a projection a little outside the point's scale-invariance range.
constexpr double kMinDistanceSlack = 0.8;
constexpr double kMaxDistanceSlack = 1.2;

FeatureGrid make_grid(const Keyframe& kf, const PinholeStereo& camera) {
  return FeatureGrid(kf.features.keypoints, camera.width_px, camera.height_px);
}

}  // namespace

int fuse_into_keyframe(Map& map, KeyframeId kf_id, const FeatureGrid& grid, const std::vector<PointId>& point_ids,
                       const PinholeStereo& camera, const FusionOptions& options, MapChanges& changes) {
  Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr || kf->culled) return 0;
  const Pose3 T_cw = kf->T_wc.inverse();
  const Eigen::Vector3d origin = kf->T_wc.translation();
  const ScalePyramid& pyramid = kf->features.pyramid;
  int fused = 0;
  for (const PointId point_id : point_ids) {
    const MapPoint* point = map.point(point_id);
    if (point == nullptr || observation_index(*point, kf_id) >= 0) continue;
    const Eigen::Vector3d p_c = T_cw * point->p_w;
    if (p_c.z() <= 0.0) continue;
    const Eigen::Vector2d uv = camera.project(p_c);
    if (!camera.in_image(uv.x(), uv.y())) continue;
    const double u_right = camera.u_right(p_c);
    const Eigen::Vector3d ray = point->p_w - origin;
    const double distance = ray.norm();
    if (distance < kMinDistanceSlack * point->min_distance_m || distance > kMaxDistanceSlack * point->max_distance_m) {
      continue;
    }
    if (ray.dot(point->normal) < options.min_view_cos * distance) continue;
    const int level = predict_level(*point, distance, pyramid);
    const float radius = options.radius_factor * pyramid.scale[static_cast<std::size_t>(level)];

    int best_distance = options.max_descriptor_distance + 1;
    int best_index = -1;
    for (const int index : grid.in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius)) {
      const std::size_t i = static_cast<std::size_t>(index);
      const Keypoint& kp = kf->features.keypoints[i];
      if (kp.octave < level - 1 || kp.octave > level) continue;
      double error2 = (uv - Eigen::Vector2d(kp.u_px, kp.v_px)).squaredNorm();
      double chi2 = options.mono_chi2;
      if (kf->features.has_stereo(i)) {
        const double du = u_right - kf->features.u_right_px[i];
        error2 += du * du;
        chi2 = options.stereo_chi2;
      }
      if (error2 * pyramid.inv_sigma2[static_cast<std::size_t>(kp.octave)] > chi2) continue;
      const int d = hamming_distance(point->descriptor, kf->features.descriptors[i]);
      if (d < best_distance) {
        best_distance = d;
        best_index = index;
      }
    }
    if (best_index < 0) continue;

    const PointId existing_id = kf->point_ids[static_cast<std::size_t>(best_index)];
    if (existing_id != kNoId && map.point(existing_id) != nullptr) {
      // Keep the better observed of the two; the other is merged into it.
      const bool keep_existing = map.point(existing_id)->observations.size() > point->observations.size();
      const PointId from = keep_existing ? point_id : existing_id;
      const PointId into = keep_existing ? existing_id : point_id;
      replace_point(map, from, into);
      changes.removed_points[from] = into;
      changes.changed_points.erase(from);
      changes.changed_points.insert(into);
    } else {
      if (existing_id != kNoId) kf->point_ids[static_cast<std::size_t>(best_index)] = kNoId;
      add_observation(map, point_id, kf_id, best_index);
      changes.changed_points.insert(point_id);
    }
    ++fused;
  }
  return fused;
}

int fuse_with_neighbours(Map& map, KeyframeId kf_id, const PinholeStereo& camera, const FusionOptions& options,
                         MapChanges& changes) {
  const Keyframe* kf = map.keyframe(kf_id);
  if (kf == nullptr) return 0;
  std::vector<KeyframeId> targets;
  std::set<KeyframeId> seen{kf_id};
  for (const KeyframeId neighbour : best_covisible(map, kf_id, options.neighbours)) {
    if (seen.insert(neighbour).second) targets.push_back(neighbour);
  }
  const std::size_t first_order = targets.size();
  for (std::size_t t = 0; t < first_order; ++t) {
    for (const KeyframeId second : best_covisible(map, targets[t], options.second_neighbours)) {
      if (seen.insert(second).second) targets.push_back(second);
    }
  }

  int fused = 0;
  for (const KeyframeId target : targets) {
    std::vector<PointId> own_points;
    for (const PointId id : map.keyframe(kf_id)->point_ids) {
      if (id != kNoId) own_points.push_back(id);
    }
    fused +=
        fuse_into_keyframe(map, target, make_grid(*map.keyframe(target), camera), own_points, camera, options, changes);
  }

  std::set<PointId> candidates;
  for (const KeyframeId target : targets) {
    for (const PointId id : map.keyframe(target)->point_ids) {
      if (id != kNoId) candidates.insert(id);
    }
  }
  fused += fuse_into_keyframe(map, kf_id, make_grid(*map.keyframe(kf_id), camera),
                              std::vector<PointId>(candidates.begin(), candidates.end()), camera, options, changes);

  for (const PointId id : map.keyframe(kf_id)->point_ids) {
    if (id != kNoId) {
      update_point_statistics(map, id);
      changes.changed_points.insert(id);
    }
  }
  return fused;
}

}  // namespace heslam

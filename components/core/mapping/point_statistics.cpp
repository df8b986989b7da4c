// Representative descriptor, viewing normal and scale-invariance distance range of a map point.
#include "components/core/mapping/point_statistics.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "components/core/mapping/map_editing.hpp"

namespace heslam {

namespace {

// The observation's descriptor with the least median Hamming distance to the others (the first of
// equal ones); `keyframe(id)` finds an observing keyframe or returns null.
template <typename FindKeyframe>
Descriptor representative_descriptor_of(const MapPoint& point, FindKeyframe keyframe) {
  std::vector<const Descriptor*> descriptors;
  descriptors.reserve(point.observations.size());
  for (const auto& [kf_id, index] : point.observations) {
    const Keyframe* kf = keyframe(kf_id);
    if (kf != nullptr) descriptors.push_back(&kf->features.descriptors[static_cast<std::size_t>(index)]);
  }
  if (descriptors.empty()) return point.descriptor;
  const std::size_t n = descriptors.size();
  // The distance matrix is symmetric: each pair once.
  std::vector<int> matrix(n * n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      matrix[i * n + j] = matrix[j * n + i] = hamming_distance(*descriptors[i], *descriptors[j]);
    }
  }
  std::size_t best = 0;
  int best_median = 1 << 30;
  std::vector<int> distances(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::copy(matrix.begin() + static_cast<std::ptrdiff_t>(i * n),
              matrix.begin() + static_cast<std::ptrdiff_t>((i + 1) * n), distances.begin());
    std::nth_element(distances.begin(), distances.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2), distances.end());
    const int median = distances[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  return *descriptors[best];
}

template <typename FindKeyframe>
void update_point_geometry_of(MapPoint& point, FindKeyframe keyframe) {
  if (point.observations.empty()) return;
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (const auto& [kf_id, index] : point.observations) {
    const Keyframe* kf = keyframe(kf_id);
    if (kf == nullptr) continue;
    const Eigen::Vector3d ray = point.p_w - kf->T_wc.translation();
    if (ray.norm() > 0.0) {
      normal_sum += ray.normalized();
      ++count;
    }
  }
  if (count > 0 && normal_sum.norm() > 0.0) point.normal = normal_sum.normalized();

  if (keyframe(point.reference_kf) == nullptr || observation_index(point, point.reference_kf) < 0) {
    point.reference_kf = point.observations.front().first;
  }
  const Keyframe& ref = *keyframe(point.reference_kf);
  const int index = observation_index(point, ref.id);
  const ScalePyramid& pyramid = ref.features.pyramid;
  const int level = ref.features.keypoints[static_cast<std::size_t>(index)].octave;
  const double distance = (point.p_w - ref.T_wc.translation()).norm();
  point.max_distance_m = static_cast<float>(distance * pyramid.scale[static_cast<std::size_t>(level)]);
  point.min_distance_m = point.max_distance_m / pyramid.scale.back();
}

template <typename FindKeyframe>
void update_point_statistics_of(MapPoint& point, FindKeyframe keyframe) {
  if (point.observations.empty()) return;
  update_point_geometry_of(point, keyframe);
  point.descriptor = representative_descriptor_of(point, keyframe);
}

}  // namespace

Descriptor representative_descriptor(const Map& map, const MapPoint& point) {
  return representative_descriptor_of(point, [&map](KeyframeId id) { return map.keyframe(id); });
}

void update_point_statistics(Map& map, PointId point_id) {
  MapPoint* point = map.point(point_id);
  if (point == nullptr) return;
  update_point_statistics_of(*point, [&map](KeyframeId id) { return std::as_const(map).keyframe(id); });
}

KeyframeIndex::KeyframeIndex(const Map& map) {
  keyframes_.reserve(map.keyframes.size());
  for (const auto& [id, kf] : map.keyframes) keyframes_.emplace(id, &kf);
}

void update_point_statistics(MapPoint& point, const KeyframeIndex& index) {
  update_point_statistics_of(point, [&index](KeyframeId id) { return index.find(id); });
}

void update_point_geometry(MapPoint& point, const KeyframeIndex& index) {
  update_point_geometry_of(point, [&index](KeyframeId id) { return index.find(id); });
}

int predict_level(const MapPoint& point, double distance_m, const ScalePyramid& pyramid) {
  if (distance_m <= 0.0) return 0;
  const double ratio = point.max_distance_m / distance_m;
  const int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(pyramid.scale_factor)));
  return std::clamp(level, 0, pyramid.levels - 1);
}

}  // namespace heslam

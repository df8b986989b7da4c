// Representative descriptor, viewing normal and scale-invariance distance range of a map point.
#include "components/core/mapping/point_statistics.hpp"

#include <algorithm>
#include <cmath>

#include "components/core/mapping/map_editing.hpp"

namespace heslam {

Descriptor representative_descriptor(const Map& map, const MapPoint& point) {
  std::vector<const Descriptor*> descriptors;
  for (const auto& [kf_id, index] : point.observations) {
    const Keyframe* kf = map.keyframe(kf_id);
    if (kf != nullptr) descriptors.push_back(&kf->features.descriptors[static_cast<std::size_t>(index)]);
  }
  if (descriptors.empty()) return point.descriptor;
  const std::size_t n = descriptors.size();
  std::size_t best = 0;
  int best_median = 1 << 30;
  std::vector<int> distances(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) distances[j] = hamming_distance(*descriptors[i], *descriptors[j]);
    std::nth_element(distances.begin(), distances.begin() + static_cast<std::ptrdiff_t>((n - 1) / 2), distances.end());
    const int median = distances[(n - 1) / 2];
    if (median < best_median) {
      best_median = median;
      best = i;
    }
  }
  return *descriptors[best];
}

void update_point_statistics(Map& map, PointId point_id) {
  MapPoint* point = map.point(point_id);
  if (point == nullptr || point->observations.empty()) return;
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (const auto& [kf_id, index] : point->observations) {
    const Keyframe* kf = map.keyframe(kf_id);
    if (kf == nullptr) continue;
    const Eigen::Vector3d ray = point->p_w - kf->T_wc.translation();
    if (ray.norm() > 0.0) {
      normal_sum += ray.normalized();
      ++count;
    }
  }
  if (count > 0 && normal_sum.norm() > 0.0) point->normal = normal_sum.normalized();

  if (map.keyframe(point->reference_kf) == nullptr || observation_index(*point, point->reference_kf) < 0) {
    point->reference_kf = point->observations.front().first;
  }
  const Keyframe& ref = *map.keyframe(point->reference_kf);
  const int index = observation_index(*point, ref.id);
  const ScalePyramid& pyramid = ref.features.pyramid;
  const int level = ref.features.keypoints[static_cast<std::size_t>(index)].octave;
  const double distance = (point->p_w - ref.T_wc.translation()).norm();
  point->max_distance_m = static_cast<float>(distance * pyramid.scale[static_cast<std::size_t>(level)]);
  point->min_distance_m = point->max_distance_m / pyramid.scale.back();
  point->descriptor = representative_descriptor(map, *point);
}

int predict_level(const MapPoint& point, double distance_m, const ScalePyramid& pyramid) {
  if (distance_m <= 0.0) return 0;
  const double ratio = point.max_distance_m / distance_m;
  const int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(pyramid.scale_factor)));
  return std::clamp(level, 0, pyramid.levels - 1);
}

}  // namespace heslam

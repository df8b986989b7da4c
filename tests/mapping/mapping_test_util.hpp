// Helpers shared by the mapping tests: a map of synthetic keyframes observing their world points.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>

#include "components/core/mapping/covisibility.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"
#include "tests/mapping/synthetic_world.hpp"

namespace heslam::test {

struct TruthMap {
  Map map;
  std::map<KeyframeId, Pose3> true_T_wc;
  std::map<PointId, Eigen::Vector3d> true_p_w;
};

// Keyframes 1..count on the circle; one map point per world point seen by at least two keyframes,
// linked to every keyframe that sees it; covisibility and parents computed.
inline TruthMap make_truth_map(const SyntheticWorld& world, int count, const ViewOptions& view_options,
                               double step_rad = 0.12) {
  TruthMap result;
  std::map<int, std::vector<std::pair<KeyframeId, int>>> seen_by;
  for (int k = 0; k < count; ++k) {
    const KeyframeId id = static_cast<KeyframeId>(k + 1);
    const Pose3 T_wc = circle_pose(k, step_rad);
    SyntheticView view = make_view(world, id, T_wc, 100 + static_cast<unsigned>(k), view_options);
    for (std::size_t i = 0; i < view.truth.size(); ++i) {
      if (view.truth[i] >= 0) seen_by[view.truth[i]].emplace_back(id, static_cast<int>(i));
    }
    result.map.keyframes.emplace(id, std::move(view.kf));
    result.true_T_wc[id] = T_wc;
  }
  std::uint64_t counter = 0;
  for (const auto& [t, observers] : seen_by) {
    if (observers.size() < 2) continue;
    MapPoint point;
    point.id = make_id(kFrontendTag, ++counter);
    point.p_w = world.points_w[static_cast<std::size_t>(t)];
    point.reference_kf = observers.front().first;
    const PointId id = point.id;
    result.map.points.emplace(id, point);
    result.true_p_w[id] = point.p_w;
    for (const auto& [kf_id, index] : observers) add_observation(result.map, id, kf_id, index);
    update_point_statistics(result.map, id);
  }
  for (const auto& [id, kf] : result.map.keyframes) update_connections(result.map, id, CovisibilityOptions{});
  return result;
}

// Largest element difference of two poses. An element loop: Eigen's vectorised 4x4 reductions trip a
// GCC 12 AVX-512 false -Wmaybe-uninitialized under -march=native.
inline double max_abs_difference(const Pose3& a, const Pose3& b) {
  double largest = 0.0;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) largest = std::max(largest, std::abs(a.matrix()(r, c) - b.matrix()(r, c)));
  }
  return largest;
}

inline double rotation_error_rad(const Pose3& a, const Pose3& b) {
  // From the trace: Eigen's AngleAxisd(Matrix3d) trips the same AVX-512 false warning.
  const double cos_angle = ((a.linear().transpose() * b.linear()).trace() - 1.0) / 2.0;
  return std::acos(std::clamp(cos_angle, -1.0, 1.0));
}

}  // namespace heslam::test

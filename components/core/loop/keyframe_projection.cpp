// Projection matching of a map point into a keyframe (see keyframe_projection.hpp).
#include "components/core/loop/keyframe_projection.hpp"

#include "components/core/mapping/point_statistics.hpp"

namespace heslam {
namespace {

// ORB-SLAM2 accepts a projection a little outside the point's scale-invariance range.
constexpr double kMinDistanceSlack = 0.8;
constexpr double kMaxDistanceSlack = 1.2;

}  // namespace

std::optional<PredictedView> predict_view(const MapPoint& point, const Pose3& T_wc, const PinholeStereo& camera,
                                          const ProjectionMatchOptions& options) {
  const Eigen::Vector3d p_c = T_wc.inverse() * point.p_w;
  if (p_c.z() <= 0.0) return std::nullopt;
  const Eigen::Vector2d uv = camera.project(p_c);
  if (!camera.in_image(uv.x(), uv.y())) return std::nullopt;
  const Eigen::Vector3d ray = point.p_w - T_wc.translation();
  const double distance = ray.norm();
  if (distance < kMinDistanceSlack * point.min_distance_m || distance > kMaxDistanceSlack * point.max_distance_m) {
    return std::nullopt;
  }
  if (ray.dot(point.normal) < options.min_view_cos * distance) return std::nullopt;
  return PredictedView{uv, distance};
}

int best_projection_match(const MapPoint& point, const Keyframe& kf, const Pose3& T_wc, const FeatureGrid& grid,
                          const PinholeStereo& camera, const ProjectionMatchOptions& options) {
  const std::optional<PredictedView> view = predict_view(point, T_wc, camera, options);
  if (!view) return -1;
  const Eigen::Vector2d& uv = view->uv_px;
  const ScalePyramid& pyramid = kf.features.pyramid;
  const int level = predict_level(point, view->distance_m, pyramid);
  const float radius = options.radius_px * pyramid.scale[static_cast<std::size_t>(level)];
  int best_distance = options.max_descriptor_distance + 1;
  int best_index = -1;
  for (const int index :
       grid.in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius, level - 1, level)) {
    const int d = hamming_distance(point.descriptor, kf.features.descriptors[static_cast<std::size_t>(index)]);
    if (d < best_distance) {
      best_distance = d;
      best_index = index;
    }
  }
  return best_index;
}

}  // namespace heslam

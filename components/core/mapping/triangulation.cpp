// Triangulation of new map points with ORB-SLAM2's acceptance checks.
#include "components/core/mapping/triangulation.hpp"

#include <cmath>

#include <Eigen/LU>

#include "components/core/mapping/covisibility.hpp"
#include "components/core/mapping/map_editing.hpp"
#include "components/core/mapping/point_statistics.hpp"
#include "components/core/mapping/triangulation_search.hpp"

namespace heslam {
namespace {

// Relative determinant below which the two rays are (numerically) parallel.
constexpr double kDegenerateDeterminant = 1e-15;

// Reprojection check of a world point in one keyframe's keypoint (stereo residual when it has depth).
bool reprojects(const Keyframe& kf, int index, const Eigen::Vector3d& p_w, const PinholeStereo& camera,
                const TriangulationOptions& options) {
  const Eigen::Vector3d p_c = kf.T_wc.inverse() * p_w;
  if (p_c.z() <= 0.0) return false;
  const std::size_t i = static_cast<std::size_t>(index);
  const Keypoint& kp = kf.features.keypoints[i];
  const double sigma2 = kf.features.pyramid.sigma2[static_cast<std::size_t>(kp.octave)];
  const Eigen::Vector2d uv = camera.project(p_c);
  double error2 = (uv - Eigen::Vector2d(kp.u_px, kp.v_px)).squaredNorm();
  if (kf.features.has_stereo(i)) {
    const double du_right = camera.u_right(p_c) - kf.features.u_right_px[i];
    error2 += du_right * du_right;
    return error2 <= options.stereo_chi2 * sigma2;
  }
  return error2 <= options.mono_chi2 * sigma2;
}

Eigen::Vector2d normalized(const Keypoint& kp, const PinholeStereo& camera) {
  return {(kp.u_px - camera.cx_px) / camera.fx_px, (kp.v_px - camera.cy_px) / camera.fy_px};
}

// Parallax angle cosine of the stereo pair at this keypoint's depth (2 if no stereo: never wins).
double stereo_parallax_cos(const Keyframe& kf, std::size_t i, const PinholeStereo& camera) {
  if (!kf.features.has_stereo(i)) return 2.0;
  return std::cos(2.0 * std::atan2(camera.baseline_m / 2.0, kf.features.depth_m[i]));
}

}  // namespace

std::optional<Eigen::Vector3d> triangulate_linear(const Pose3& T_cw1, const Pose3& T_cw2, const Eigen::Vector2d& x1,
                                                  const Eigen::Vector2d& x2) {
  const Eigen::Matrix<double, 3, 4> P1 = T_cw1.matrix().topRows<3>();
  const Eigen::Matrix<double, 3, 4> P2 = T_cw2.matrix().topRows<3>();
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  // A [X; 1] = 0 solved for X in the least-squares sense (normal equations of a 4x3 system): the
  // same minimiser as the DLT's smallest singular vector for points not at infinity.
  const Eigen::Matrix<double, 4, 3> B = A.leftCols<3>();
  const Eigen::Matrix3d normal = B.transpose() * B;
  const double scale = normal.trace();
  if (!(scale > 0.0) || std::abs(normal.determinant()) < kDegenerateDeterminant * scale * scale * scale) {
    return std::nullopt;
  }
  return Eigen::Vector3d(normal.inverse() * (-B.transpose() * A.col(3)));
}

std::optional<Eigen::Vector3d> triangulate_match(const Keyframe& kf1, int i1, const Keyframe& kf2, int i2,
                                                 const PinholeStereo& camera, const TriangulationOptions& options) {
  const std::size_t a = static_cast<std::size_t>(i1);
  const std::size_t b = static_cast<std::size_t>(i2);
  const Keypoint& kp1 = kf1.features.keypoints[a];
  const Keypoint& kp2 = kf2.features.keypoints[b];
  const Eigen::Vector2d x1 = normalized(kp1, camera);
  const Eigen::Vector2d x2 = normalized(kp2, camera);
  const Eigen::Vector3d ray1 = kf1.T_wc.linear() * x1.homogeneous();
  const Eigen::Vector3d ray2 = kf2.T_wc.linear() * x2.homogeneous();
  const double rays_cos = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
  const double stereo1_cos = stereo_parallax_cos(kf1, a, camera);
  const double stereo2_cos = stereo_parallax_cos(kf2, b, camera);
  const double stereo_cos = std::min(stereo1_cos, stereo2_cos);
  const bool any_stereo = kf1.features.has_stereo(a) || kf2.features.has_stereo(b);

  std::optional<Eigen::Vector3d> p_w;
  if (rays_cos < stereo_cos && rays_cos > 0.0 && (any_stereo || rays_cos < options.min_parallax_cos)) {
    p_w = triangulate_linear(kf1.T_wc.inverse(), kf2.T_wc.inverse(), x1, x2);
  } else if (kf1.features.has_stereo(a) && stereo1_cos < stereo2_cos) {
    p_w = kf1.T_wc * camera.unproject(kp1.u_px, kp1.v_px, kf1.features.depth_m[a]);
  } else if (kf2.features.has_stereo(b) && stereo2_cos < stereo1_cos) {
    p_w = kf2.T_wc * camera.unproject(kp2.u_px, kp2.v_px, kf2.features.depth_m[b]);
  }
  if (!p_w || !p_w->allFinite()) return std::nullopt;
  if (!reprojects(kf1, i1, *p_w, camera, options) || !reprojects(kf2, i2, *p_w, camera, options)) {
    return std::nullopt;
  }

  const double distance1 = (*p_w - kf1.T_wc.translation()).norm();
  const double distance2 = (*p_w - kf2.T_wc.translation()).norm();
  if (distance1 <= 0.0 || distance2 <= 0.0) return std::nullopt;
  const double distance_ratio = distance2 / distance1;
  const double octave_ratio = kf1.features.pyramid.scale[static_cast<std::size_t>(kp1.octave)] /
                              kf2.features.pyramid.scale[static_cast<std::size_t>(kp2.octave)];
  const double factor = options.scale_ratio_factor * kf1.features.pyramid.scale_factor;
  if (distance_ratio * factor < octave_ratio || distance_ratio > octave_ratio * factor) return std::nullopt;
  return p_w;
}

std::vector<PointId> create_new_points(Map& map, KeyframeId kf_id, const PinholeStereo& camera,
                                       const TriangulationOptions& options, std::uint8_t creator_tag,
                                       std::uint64_t& next_counter) {
  std::vector<PointId> created;
  const Keyframe* kf1 = map.keyframe(kf_id);
  if (kf1 == nullptr) return created;
  for (const KeyframeId neighbour_id : best_covisible(map, kf_id, options.neighbours)) {
    const Keyframe& kf2 = *map.keyframe(neighbour_id);
    const Keyframe& kf1_now = *map.keyframe(kf_id);
    // Stereo: a baseline shorter than the stereo baseline adds nothing to the stereo depth.
    if ((kf2.T_wc.translation() - kf1_now.T_wc.translation()).norm() < camera.baseline_m) continue;
    for (const auto& [i1, i2] : search_for_triangulation(kf1_now, kf2, camera, options)) {
      const auto p_w = triangulate_match(kf1_now, i1, kf2, i2, camera, options);
      if (!p_w) continue;
      MapPoint point;
      point.id = make_id(creator_tag, ++next_counter);
      point.map_id = kf1_now.map_id;  // both keyframes are in it: covisibility never crosses maps
      point.p_w = *p_w;
      point.reference_kf = kf_id;
      const PointId id = point.id;
      map.points.emplace(id, std::move(point));
      add_observation(map, id, kf_id, i1);
      add_observation(map, id, neighbour_id, i2);
      update_point_statistics(map, id);
      created.push_back(id);
    }
  }
  return created;
}

}  // namespace heslam

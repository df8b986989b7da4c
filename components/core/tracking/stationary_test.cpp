// Nested likelihood-ratio tests: still, rotating in place, or moving (stationary_test.hpp).
#include "components/core/tracking/stationary_test.hpp"

#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

#include "components/core/tracking/motion_only_ba.hpp"
#include "components/core/tracking/optimize_frame.hpp"

namespace heslam {
namespace {

// Gauss-Newton on a 3-parameter rotation converges in a few steps from the last pose.
constexpr int kRotationIterations = 5;
constexpr double kRotationStepConverged = 1e-10;  // radians

// The rotation about the last camera centre that best explains the observations (least squares,
// whitened as in the motion-only BA; the observations are inliers already, so no robust kernel).
// Points are expressed in the last camera's frame, p_c = R * q; R is updated on the left.
Pose3 rotation_about_centre(std::vector<PoseObservation> observations, const PinholeStereo& camera,
                            const TrackerOptions& options, const Pose3& T_wc_last) {
  const Pose3 T_cw_last = T_wc_last.inverse();
  for (PoseObservation& obs : observations) obs.p_w = T_cw_last * obs.p_w;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (int iteration = 0; iteration < kRotationIterations; ++iteration) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (const PoseObservation& obs : observations) {
      const Eigen::Vector3d p = R * obs.p_w;
      if (p.z() <= 0.0) continue;
      const double inv_z = 1.0 / p.z();
      const double sqrt_info = std::sqrt(obs.inv_sigma2);
      // d p / d omega for p' = (I + [omega]x) p is -[p]x.
      Eigen::Matrix3d dp_domega;
      dp_domega << 0.0, p.z(), -p.y(), -p.z(), 0.0, p.x(), p.y(), -p.x(), 0.0;
      const auto add = [&](const Eigen::RowVector3d& dresidual_dp, double residual, double weight) {
        const Eigen::RowVector3d J = weight * dresidual_dp * dp_domega;
        H += J.transpose() * J;
        g += J.transpose() * (weight * residual);
      };
      add({camera.fx_px * inv_z, 0.0, -camera.fx_px * p.x() * inv_z * inv_z},
          camera.fx_px * p.x() * inv_z + camera.cx_px - obs.u_px, sqrt_info);
      add({0.0, camera.fy_px * inv_z, -camera.fy_px * p.y() * inv_z * inv_z},
          camera.fy_px * p.y() * inv_z + camera.cy_px - obs.v_px, sqrt_info);
      if (obs.stereo()) {
        add({0.0, 0.0, -camera.bf() * inv_z * inv_z}, camera.bf() * inv_z - (obs.u_px - obs.u_right_px),
            sqrt_info / (options.disparity_sigma_ratio * obs.disparity_sigma_scale));
      }
    }
    const Eigen::Vector3d omega = H.ldlt().solve(-g);
    if (!omega.allFinite() || omega.norm() < kRotationStepConverged) break;
    R = Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix() * R;
  }
  Pose3 R_c_last = Pose3::Identity();
  R_c_last.linear() = R;
  return (R_c_last * T_cw_last).inverse();
}

}  // namespace

const char* to_string(FrameMotion motion) {
  switch (motion) {
    case FrameMotion::kMoving: return "moving";
    case FrameMotion::kRotatingInPlace: return "rotating";
    case FrameMotion::kStill: return "still";
  }
  return "unknown";
}

StationaryTestResult test_stationary(const Frame& frame, const Map& map, const PinholeStereo& camera,
                                     const TrackerOptions& options, const Pose3& T_wc_last) {
  StationaryTestResult result{FrameMotion::kMoving, frame.T_wc};
  if (!(options.stationary_test_chi2 > 0.0)) return result;
  const std::vector<PoseObservation> observations = frame_observations(frame, map);
  const auto chi2_at = [&](const Pose3& T_wc) {
    const Pose3 T_cw = T_wc.inverse();
    double sum = 0.0;
    for (const PoseObservation& obs : observations)
      sum += observation_chi2(camera, obs, T_cw, options.disparity_sigma_ratio);
    return sum;
  };
  const double at_optimum = chi2_at(frame.T_wc);
  if (chi2_at(T_wc_last) - at_optimum < options.stationary_test_chi2) return {FrameMotion::kStill, T_wc_last};
  if (!(options.rotation_only_test_chi2 > 0.0)) return result;
  const Pose3 rotated = rotation_about_centre(observations, camera, options, T_wc_last);
  if (chi2_at(rotated) - at_optimum < options.rotation_only_test_chi2) return {FrameMotion::kRotatingInPlace, rotated};
  return result;
}

}  // namespace heslam

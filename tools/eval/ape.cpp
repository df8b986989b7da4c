// Absolute pose error after alignment.
#include "tools/eval/ape.hpp"

#include <numbers>

namespace heslam::eval {

ApeResult compute_ape(const AlignedPair& pair, const ApeOptions& options) {
  ApeResult result;
  result.align = options.align;
  result.gt = pair.gt;
  result.est_aligned = pair.est;
  result.alignment = compute_alignment(pair.gt, pair.est, options.align);
  apply_sim3(result.est_aligned, result.alignment);

  const std::size_t n = pair.size();
  result.translation_errors_m.reserve(n);
  result.rotation_errors_deg.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Pose3& T_gt = result.gt.poses_wc[i];
    const Pose3& T_est = result.est_aligned.poses_wc[i];
    result.translation_errors_m.push_back((T_gt.translation() - T_est.translation()).norm());
    const Eigen::Matrix3d R_error = T_gt.linear().transpose() * T_est.linear();
    result.rotation_errors_deg.push_back(rotation_angle_rad(R_error) * 180.0 / std::numbers::pi);
  }
  result.translation_m = compute_stats(result.translation_errors_m);
  result.rotation_deg = compute_stats(result.rotation_errors_deg);
  return result;
}

ApeResult compute_ape(const Trajectory& gt, const Trajectory& est, const ApeOptions& options,
                      const AssociationOptions& association) {
  return compute_ape(associate(gt, est, association), options);
}

}  // namespace heslam::eval

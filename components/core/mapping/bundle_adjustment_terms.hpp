// Ceres building blocks of the bundle adjustment: a world->camera pose block with a left-multiplied
// SO(3) x R^3 perturbation, and the analytic stereo / monocular reprojection residual.
//
// Pose block layout (7 doubles): quaternion x y z w of R_cw, then t_cw. The residual's Jacobian is
// written directly in the 6-dof tangent space (first 6 columns; the 7th is zero) and the manifold's
// PlusJacobian is [I6; 0] -- the usual way to give Ceres analytic Lie-group Jacobians. Analytic
// Jacobians are ~3x cheaper than autodiff through angle-axis rotations, which is most of a local BA.
#pragma once

#include <array>

#include <ceres/ceres.h>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"

namespace heslam {

using PoseBlock = std::array<double, 7>;

PoseBlock to_pose_block(const Pose3& T_wc);
Pose3 from_pose_block(const PoseBlock& block);  // returns T_wc
Eigen::Vector3d transform_to_camera(const PoseBlock& block, const Eigen::Vector3d& p_w);

// Plus(x, [w, r]) = (Exp(w) R, t + r): rotation perturbed on the left, translation additively.
class PoseManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

// Whitened (u, v) or (u, v, disparity) residual of one observation; `stereo` selects 3 residuals.
// The disparity error (bf / z against u - u_right) has its own weight, inv_sigma / disparity_sigma_ratio,
// as in the tracker's motion-only BA (motion_only_ba.hpp), so frontend and mapper agree on the model.
class ReprojectionCost : public ceres::CostFunction {
 public:
  ReprojectionCost(const PinholeStereo& camera, double u_px, double v_px, double u_right_px, double inv_sigma,
                   bool stereo, double disparity_sigma_ratio);
  bool Evaluate(const double* const* parameters, double* residuals, double** jacobians) const override;

 private:
  double fx_, fy_, cx_, cy_, bf_, u_, v_, disparity_, weight_, disparity_weight_;
  bool stereo_;
};

}  // namespace heslam

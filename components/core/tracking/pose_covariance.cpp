// Pose covariance from motion-only BA's information (see pose_covariance.hpp).
#include "components/core/tracking/pose_covariance.hpp"

#include <cmath>

#include <Eigen/Cholesky>

namespace heslam {
namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Row6 = Eigen::Matrix<double, 1, 6>;

// [v]x: the matrix of v x (.)
Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// The parameters are motion_only_ba's: T_cw' = (Exp(w) R_cw, t_cw + r) over [w, r].
void add_row(const Row6& jacobian, double residual, Matrix6& H, double& chi2, int& rows) {
  H.noalias() += jacobian.transpose() * jacobian;
  chi2 += residual * residual;
  ++rows;
}

}  // namespace

std::optional<PoseCovariance> pose_covariance(const PinholeStereo& camera,
                                              const std::vector<PoseObservation>& observations, const Pose3& T_cw,
                                              double disparity_sigma_ratio) {
  const Eigen::Matrix3d R = T_cw.rotation();
  const Eigen::Vector3d t = T_cw.translation();
  Matrix6 H = Matrix6::Zero();
  double chi2 = 0.0;
  int rows = 0;
  for (const PoseObservation& obs : observations) {
    const Eigen::Vector3d p_r = R * obs.p_w;
    const Eigen::Vector3d p_c = p_r + t;
    if (!(p_c.z() > 0.0)) continue;
    const double s = std::sqrt(obs.inv_sigma2);
    const double inv_z = 1.0 / p_c.z();
    // d(p_c)/d[w, r] = [-[p_r]x  I]
    Eigen::Matrix<double, 3, 6> dp;
    dp << skew(-p_r), Eigen::Matrix3d::Identity();
    const Eigen::Vector2d uv = camera.project(p_c);
    const Eigen::RowVector3d du(camera.fx_px * inv_z, 0.0, -camera.fx_px * p_c.x() * inv_z * inv_z);
    const Eigen::RowVector3d dv(0.0, camera.fy_px * inv_z, -camera.fy_px * p_c.y() * inv_z * inv_z);
    add_row(s * du * dp, s * (uv.x() - obs.u_px), H, chi2, rows);
    add_row(s * dv * dp, s * (uv.y() - obs.v_px), H, chi2, rows);
    if (obs.stereo()) {
      const double sd = s / (disparity_sigma_ratio * obs.disparity_sigma_scale);
      const Eigen::RowVector3d dd(0.0, 0.0, -camera.bf() * inv_z * inv_z);
      add_row(sd * dd * dp, sd * (camera.bf() * inv_z - (obs.u_px - obs.u_right_px)), H, chi2, rows);
    }
  }
  if (rows <= 6) return std::nullopt;
  const Eigen::LDLT<Matrix6> ldlt(H);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(ldlt.vectorD().minCoeff() > 0.0)) return std::nullopt;
  PoseCovariance out;
  out.rows = rows;
  out.variance_factor = chi2 / static_cast<double>(rows - 6);
  const Matrix6 covariance_cw = out.variance_factor * ldlt.solve(Matrix6::Identity());
  // T_wc = T_cw^-1: rotation = -R^T w, delta = -R^T [t]x w - R^T r (first order).
  Matrix6 G = Matrix6::Zero();
  G.block<3, 3>(0, 0) = -R.transpose();
  G.block<3, 3>(3, 0) = -R.transpose() * skew(t);
  G.block<3, 3>(3, 3) = -R.transpose();
  out.covariance_wc = G * covariance_cw * G.transpose();
  out.covariance_wc = 0.5 * (out.covariance_wc + out.covariance_wc.transpose()).eval();
  if (!out.covariance_wc.allFinite()) return std::nullopt;
  return out;
}

}  // namespace heslam

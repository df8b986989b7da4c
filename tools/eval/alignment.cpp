// Umeyama (1991) least-squares similarity between two point sets, and the alignment modes.
#include "tools/eval/alignment.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace heslam::eval {

namespace {

// Fewer points leave the rotation undetermined.
constexpr std::size_t kMinAlignmentPairs = 3;

std::vector<Eigen::Vector3d> positions(const Trajectory& trajectory) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(trajectory.size());
  for (const Pose3& T : trajectory.poses_wc) out.push_back(T.translation());
  return out;
}

}  // namespace

std::optional<AlignMode> parse_align_mode(std::string_view name) {
  if (name == "none") return AlignMode::none;
  if (name == "origin") return AlignMode::origin;
  if (name == "se3") return AlignMode::se3;
  if (name == "sim3") return AlignMode::sim3;
  return std::nullopt;
}

const char* align_mode_name(AlignMode mode) {
  switch (mode) {
    case AlignMode::none: return "none";
    case AlignMode::origin: return "origin";
    case AlignMode::se3: return "se3";
    case AlignMode::sim3: return "sim3";
  }
  return "?";
}

Sim3 umeyama(std::span<const Eigen::Vector3d> from, std::span<const Eigen::Vector3d> to, bool with_scale) {
  if (from.size() != to.size()) throw std::runtime_error("alignment: point sets differ in size");
  const std::size_t n = from.size();
  if (n < kMinAlignmentPairs) {
    throw std::runtime_error("alignment needs at least 3 pose pairs, got " + std::to_string(n));
  }
  Eigen::Vector3d mean_from = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_to = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    mean_from += from[i];
    mean_to += to[i];
  }
  mean_from /= static_cast<double>(n);
  mean_to /= static_cast<double>(n);

  double sigma_from = 0.0;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d a = from[i] - mean_from;
    sigma_from += a.squaredNorm();
    cov += (to[i] - mean_to) * a.transpose();
  }
  sigma_from /= static_cast<double>(n);
  cov /= static_cast<double>(n);
  if (!(sigma_from > 0.0)) throw std::runtime_error("alignment: the estimate does not move (all positions equal)");

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;

  Sim3 result;
  result.R = svd.matrixU() * S * svd.matrixV().transpose();
  result.scale = with_scale ? (svd.singularValues().asDiagonal() * S).trace() / sigma_from : 1.0;
  result.t = mean_to - result.scale * (result.R * mean_from);
  return result;
}

Sim3 compute_alignment(const Trajectory& gt, const Trajectory& est, AlignMode mode) {
  switch (mode) {
    case AlignMode::none: return Sim3{};
    case AlignMode::origin: {
      // T = T_gt0 * T_est0^-1 puts the estimate's first pose onto the ground truth's.
      const Pose3 T = gt.poses_wc.front() * est.poses_wc.front().inverse();
      Sim3 result;
      result.R = T.linear();
      result.t = T.translation();
      return result;
    }
    case AlignMode::se3:
    case AlignMode::sim3: {
      const std::vector<Eigen::Vector3d> from = positions(est);
      const std::vector<Eigen::Vector3d> to = positions(gt);
      return umeyama(from, to, mode == AlignMode::sim3);
    }
  }
  return Sim3{};
}

std::optional<std::string> alignment_degeneracy(const Trajectory& gt, const Trajectory& est, const Sim3& fit) {
  const std::size_t n = std::min(gt.size(), est.size());
  if (n == 0) return std::nullopt;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) mean += gt.poses_wc[i].translation();
  mean /= static_cast<double>(n);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double squared_residuals = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = gt.poses_wc[i].translation();
    covariance += (p - mean) * (p - mean).transpose();
    const Eigen::Vector3d moved = fit.scale * (fit.R * est.poses_wc[i].translation()) + fit.t;
    squared_residuals += (p - moved).squaredNorm();
  }
  covariance /= static_cast<double>(n);
  const double residual_m = std::sqrt(squared_residuals / static_cast<double>(n));
  // Ascending: the two smaller variances are the spread across the main axis.
  const Eigen::Vector3d variances = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues();
  const double across_m = std::sqrt(std::max(0.0, variances(0)) + std::max(0.0, variances(1)));
  const double uncertainty_rad = across_m > 0.0 ? residual_m / across_m : INFINITY;
  if (uncertainty_rad <= kMaxAlignmentRotationUncertaintyRad) return std::nullopt;
  char text[320];
  std::snprintf(text, sizeof text,
                "the alignment's rotation is ill-determined: the ground truth spreads %.3g m across its main axis "
                "(%.3g m along it) and the fit leaves %.3g m RMS, so the rotation is uncertain by about %.0f deg",
                across_m, std::sqrt(std::max(0.0, variances(2))), residual_m,
                std::min(180.0, uncertainty_rad * 180.0 / M_PI));
  return std::string(text);
}

}  // namespace heslam::eval

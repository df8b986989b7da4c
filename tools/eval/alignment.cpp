// Umeyama (1991) least-squares similarity between two point sets, and the alignment modes.
#include "tools/eval/alignment.hpp"

#include <stdexcept>
#include <string>
#include <vector>

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

}  // namespace heslam::eval

// Aligning an estimate to the ground truth before measuring: Umeyama SE(3) / Sim(3) on the paired
// positions, the first pose (origin), or nothing.
//
// API:
//   Sim3 S = umeyama(est_positions, gt_positions, /*with_scale=*/true);   // gt ~ s R est + t
//   Sim3 S = compute_alignment(pair.gt, pair.est, AlignMode::se3);
//   apply_sim3(est, S);                                                    // (trajectory.hpp)
// umeyama() is Umeyama 1991 exactly as evo and kitti-odom-eval implement it (population
// covariances, reflection fix by det(U) det(V)). Throws std::runtime_error for fewer than 3 pairs or
// a degenerate (single point) estimate.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "tools/eval/trajectory.hpp"

namespace heslam::eval {

enum class AlignMode {
  none,    // compare as given
  origin,  // move the estimate so that its first pose equals the ground truth's first pose
  se3,     // Umeyama rotation + translation (stereo / RGB-D: metric scale)
  sim3,    // Umeyama rotation + translation + scale (monocular)
};

// "none", "origin", "se3", "sim3"; nullopt otherwise.
std::optional<AlignMode> parse_align_mode(std::string_view name);
const char* align_mode_name(AlignMode mode);

Sim3 umeyama(std::span<const Eigen::Vector3d> from, std::span<const Eigen::Vector3d> to, bool with_scale);

// The transform that maps the estimate onto the ground truth; `gt` and `est` are paired row by row.
Sim3 compute_alignment(const Trajectory& gt, const Trajectory& est, AlignMode mode);

// Why a fitted se3 / sim3 alignment (`fit`, from compute_alignment) leaves the rotation undetermined,
// or nullopt when it does not. The positions fix the rotation about an axis only through their spread
// across it: a near-still trajectory, or one along a straight line, gives a rotation chosen by the
// noise. Its uncertainty is estimated as the fit's residual RMS over the ground truth's spread across
// its main axis (sqrt of the covariance's two smaller eigenvalues summed); above
// kMaxAlignmentRotationUncertaintyRad the reason is one line with both figures.
inline constexpr double kMaxAlignmentRotationUncertaintyRad = 0.05;  // about 3 deg
std::optional<std::string> alignment_degeneracy(const Trajectory& gt, const Trajectory& est, const Sim3& fit);

}  // namespace heslam::eval

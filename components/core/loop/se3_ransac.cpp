// SE(3) RANSAC: Umeyama hypotheses on seeded minimal samples, two-image chi-square inliers,
// closed-form then Ceres two-view stereo refinement on the inliers.
// GCC 12 with -march=native (AVX) reports Eigen::umeyama's vectorised loads of 3-vectors as
// -Warray-bounds: a known false positive, as in mapping/bundle_adjustment_terms.cpp.
#pragma GCC diagnostic ignored "-Warray-bounds"
#include "components/core/loop/se3_ransac.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <Eigen/Geometry>

namespace heslam {
namespace {

constexpr int kSampleSize = 3;  // three non-collinear points fix a rigid transform
// Squared norm of (b - a) x (c - a) (m^4, four times the squared triangle area) below which a sample
// is near-collinear, so its rotation about that line is unstable: skipped (~3 cm x 3 cm triangles).
constexpr double kMinSampleCross2 = 1e-6;
constexpr int kClosedFormRefinements = 2;  // reclassify after each: the refined pose gains inliers
constexpr int kCeresIterations = 10;       // ORB-SLAM2 OptimizeSim3: 5 + up to 10 LM iterations
// The two-view BA runs again from the first one's result and inliers: the RANSAC hypothesis can be
// poor (Umeyama weighs the far points' poor stereo depth fully). Measured on a loop pair with 60 %
// outliers: hypothesis 85 mm / 1.1 deg, one run 13.8 mm / 0.20 deg, two runs 8.8 mm / 0.13 deg.
constexpr int kBundleRefinements = 2;

Pose3 align(const std::vector<Se3Correspondence>& all, const std::vector<int>& subset) {
  Eigen::Matrix3Xd from(3, subset.size());
  Eigen::Matrix3Xd to(3, subset.size());
  for (std::size_t k = 0; k < subset.size(); ++k) {
    from.col(static_cast<Eigen::Index>(k)) = all[static_cast<std::size_t>(subset[k])].p_b;
    to.col(static_cast<Eigen::Index>(k)) = all[static_cast<std::size_t>(subset[k])].p_a;
  }
  Pose3 T_ab = Pose3::Identity();
  T_ab.matrix() = Eigen::umeyama(from, to, false);
  return T_ab;
}

bool well_spread(const std::vector<Se3Correspondence>& all, const std::vector<int>& sample) {
  const Eigen::Vector3d a = all[static_cast<std::size_t>(sample[0])].p_b;
  const Eigen::Vector3d b = all[static_cast<std::size_t>(sample[1])].p_b;
  const Eigen::Vector3d c = all[static_cast<std::size_t>(sample[2])].p_b;
  return (b - a).cross(c - a).squaredNorm() > kMinSampleCross2;
}

// Squared whitened reprojection error of `p_c` against a keypoint; infinite behind the camera.
double chi2_of(const PinholeStereo& camera, const Eigen::Vector3d& p_c, const Eigen::Vector2d& uv_px, double sigma2) {
  if (p_c.z() <= 0.0) return std::numeric_limits<double>::infinity();
  return (camera.project(p_c) - uv_px).squaredNorm() / sigma2;
}

int classify(const PinholeStereo& camera, const std::vector<Se3Correspondence>& all, const Pose3& T_ab,
             double chi2_threshold, std::vector<bool>& inlier) {
  const Pose3 T_ba = T_ab.inverse();
  inlier.assign(all.size(), false);
  int count = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const Se3Correspondence& c = all[i];
    if (chi2_of(camera, T_ab * c.p_b, c.uv_a_px, c.sigma2_a) >= chi2_threshold) continue;
    if (chi2_of(camera, T_ba * c.p_a, c.uv_b_px, c.sigma2_b) >= chi2_threshold) continue;
    inlier[i] = true;
    ++count;
  }
  return count;
}

// Stereo observations of one point in both keyframes, with the point (in A's frame) free: the
// keypoint (u, v) in each image and the disparity bf / z its stereo depth stands for, whitened by the
// keypoint's level. Freeing the points matters: their stereo depth is much less precise than the
// two-view parallax, and with fixed points the depth error leaks into the transform.
// Parameters: angle-axis and translation of T_ab, the point in A.
struct TwoViewStereoResidual {
  TwoViewStereoResidual(const PinholeStereo& camera, const Se3Correspondence& c, double disparity_sigma_ratio)
      : fx(camera.fx_px),
        fy(camera.fy_px),
        cx(camera.cx_px),
        cy(camera.cy_px),
        bf(camera.bf()),
        c(c),
        disparity_a(camera.bf() / c.p_a.z()),
        disparity_b(camera.bf() / c.p_b.z()),
        inv_sigma_a(1.0 / std::sqrt(c.sigma2_a)),
        inv_sigma_b(1.0 / std::sqrt(c.sigma2_b)),
        inv_disparity_ratio(1.0 / disparity_sigma_ratio) {}

  template <typename T>
  bool operator()(const T* rotation, const T* translation, const T* p_a, T* residuals) const {
    const T minus_rotation[3] = {-rotation[0], -rotation[1], -rotation[2]};
    const T shifted[3] = {p_a[0] - translation[0], p_a[1] - translation[1], p_a[2] - translation[2]};
    T p_b[3];
    ceres::AngleAxisRotatePoint(minus_rotation, shifted, p_b);
    if (p_a[2] <= T(0) || p_b[2] <= T(0)) return false;
    residuals[0] = inv_sigma_a * (fx * p_a[0] / p_a[2] + cx - c.uv_a_px.x());
    residuals[1] = inv_sigma_a * (fy * p_a[1] / p_a[2] + cy - c.uv_a_px.y());
    residuals[2] = inv_sigma_a * inv_disparity_ratio * (bf / p_a[2] - disparity_a);
    residuals[3] = inv_sigma_b * (fx * p_b[0] / p_b[2] + cx - c.uv_b_px.x());
    residuals[4] = inv_sigma_b * (fy * p_b[1] / p_b[2] + cy - c.uv_b_px.y());
    residuals[5] = inv_sigma_b * inv_disparity_ratio * (bf / p_b[2] - disparity_b);
    return true;
  }

  double fx, fy, cx, cy, bf;
  Se3Correspondence c;
  double disparity_a, disparity_b, inv_sigma_a, inv_sigma_b, inv_disparity_ratio;
};

Pose3 refine_reprojection(const PinholeStereo& camera, const std::vector<Se3Correspondence>& all,
                          const std::vector<bool>& inlier, const Pose3& T_ab, const Se3RansacOptions& options) {
  const Eigen::AngleAxisd angle_axis(T_ab.rotation());
  Eigen::Vector3d rotation = angle_axis.angle() * angle_axis.axis();
  Eigen::Vector3d translation = T_ab.translation();
  std::vector<Eigen::Vector3d> points;  // in A, one per inlier; reserved so the blocks never move
  points.reserve(all.size());
  ceres::Problem problem;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (!inlier[i] || all[i].p_a.z() <= 0.0 || all[i].p_b.z() <= 0.0) continue;
    points.push_back(all[i].p_a);
    // Ceres owns cost and loss (the problem's default ownership).
    auto* cost = new ceres::AutoDiffCostFunction<TwoViewStereoResidual, 6, 3, 3, 3>(
        new TwoViewStereoResidual(camera, all[i], options.disparity_sigma_ratio));
    auto* loss = new ceres::HuberLoss(std::sqrt(options.chi2_threshold));
    problem.AddResidualBlock(cost, loss, rotation.data(), translation.data(), points.back().data());
    ordering->AddElementToGroup(points.back().data(), 0);
  }
  if (points.empty()) return T_ab;
  ordering->AddElementToGroup(rotation.data(), 1);
  ordering->AddElementToGroup(translation.data(), 1);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_SCHUR;
  solver_options.linear_solver_ordering = ordering;
  solver_options.max_num_iterations = kCeresIterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  Pose3 refined = Pose3::Identity();
  const double angle = rotation.norm();
  refined.linear() =
      angle > 0.0 ? Eigen::AngleAxisd(angle, rotation / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  refined.translation() = translation;
  return refined;
}

}  // namespace

std::optional<Se3RansacResult> Se3Ransac::compute(const PinholeStereo& camera,
                                                  const std::vector<Se3Correspondence>& correspondences) const {
  const int n = static_cast<int>(correspondences.size());
  const int min_inliers = std::max(kSampleSize, options_.min_inliers);
  if (n < min_inliers) return std::nullopt;

  // mt19937_64's output sequence is fixed by the standard; sampling uses it directly (no distribution
  // objects, whose algorithms differ between standard libraries), as PnpRansac does.
  std::mt19937_64 rng(options_.seed);
  Se3RansacResult best;
  std::vector<bool> inlier;
  std::vector<int> sample;
  int needed_iterations = options_.max_iterations;
  int iteration = 0;
  for (; iteration < needed_iterations; ++iteration) {
    sample.clear();
    while (static_cast<int>(sample.size()) < kSampleSize) {
      const int index = static_cast<int>(rng() % static_cast<std::uint64_t>(n));
      if (std::find(sample.begin(), sample.end(), index) == sample.end()) sample.push_back(index);
    }
    if (!well_spread(correspondences, sample)) continue;
    const Pose3 T_ab = align(correspondences, sample);
    if (!T_ab.matrix().allFinite()) continue;
    const int count = classify(camera, correspondences, T_ab, options_.chi2_threshold, inlier);
    if (count <= best.inliers) continue;
    best.inliers = count;
    best.T_ab = T_ab;
    best.inlier = inlier;
    const double p_all_inliers = std::pow(static_cast<double>(count) / n, kSampleSize);
    if (p_all_inliers >= 1.0) {
      needed_iterations = iteration + 1;
    } else {
      const double k = std::log(1.0 - options_.probability) / std::log(1.0 - p_all_inliers);
      needed_iterations = std::min(options_.max_iterations, static_cast<int>(std::ceil(k)));
    }
  }
  best.iterations = iteration;
  if (best.inliers < min_inliers) return std::nullopt;

  // A closed-form refinement is kept only when it does not lose inliers (it fits the noisy stereo
  // points, so it can be worse than the hypothesis). The two-view BA is the maximum-likelihood
  // transform: kept whenever enough inliers agree with it, even if a borderline one drops out.
  const auto accept = [&](const Pose3& candidate, int required_inliers) {
    if (!candidate.matrix().allFinite()) return false;
    const int count = classify(camera, correspondences, candidate, options_.chi2_threshold, inlier);
    if (count < required_inliers) return false;
    best.T_ab = candidate;
    best.inlier = inlier;
    best.inliers = count;
    return true;
  };
  for (int refinement = 0; refinement < kClosedFormRefinements; ++refinement) {
    std::vector<int> subset;
    for (int i = 0; i < n; ++i) {
      if (best.inlier[static_cast<std::size_t>(i)]) subset.push_back(i);
    }
    if (!accept(align(correspondences, subset), best.inliers)) break;
  }
  for (int refinement = 0; options_.refine_reprojection && refinement < kBundleRefinements; ++refinement) {
    if (!accept(refine_reprojection(camera, correspondences, best.inlier, best.T_ab, options_), min_inliers)) break;
  }
  if (best.inliers < min_inliers) return std::nullopt;
  return best;
}

}  // namespace heslam

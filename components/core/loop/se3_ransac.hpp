// Relative pose of two stereo keyframes from 3D-3D correspondences with outliers: RANSAC over
// minimal samples of three, closed-form rigid alignment (Umeyama without scale), inliers by their
// reprojection error in BOTH images, refined on the inliers (closed form, then a small two-view BA). The loop closer's
// geometric check.
//
// Stereo gives metric depth, so the transform is SE(3) (ORB-SLAM2's Sim3Solver with fixed scale).
// Seeded, so the same input and seed give the same transform bit for bit.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"

namespace heslam {

// One matched map point seen by keyframes A and B: its position in each camera frame and the
// keypoint that observes it in each image, with that keypoint's variance (level scale squared).
struct Se3Correspondence {
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_b = Eigen::Vector3d::Zero();
  Eigen::Vector2d uv_a_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d uv_b_px = Eigen::Vector2d::Zero();
  double sigma2_a = 1.0;
  double sigma2_b = 1.0;
};

struct Se3RansacOptions {
  int max_iterations = 300;       // ORB-SLAM2's Sim3 RANSAC budget per candidate
  double probability = 0.99;      // stop when a better model is this unlikely to exist
  double chi2_threshold = 9.210;  // per image, squared error / sigma2 (ORB-SLAM2: 2-dof chi2 at 99 %)
  int min_inliers = 20;           // fewer: no transform (ORB-SLAM2's Sim3Solver minimum)
  // After the closed-form refinement, a Ceres refinement of T_ab and the inlier points on their
  // stereo observations in both keyframes (ORB-SLAM2's OptimizeSim3 keeps the points fixed).
  bool refine_reprojection = true;
  double disparity_sigma_ratio = 0.5;  // disparity sigma / keypoint sigma, as the bundle adjustments
  std::uint64_t seed = 1;
};

struct Se3RansacResult {
  Pose3 T_ab = Pose3::Identity();  // p_a = T_ab * p_b
  std::vector<bool> inlier;        // per correspondence
  int inliers = 0;
  int iterations = 0;  // RANSAC hypotheses drawn
};

class Se3Ransac {
 public:
  explicit Se3Ransac(const Se3RansacOptions& options = {}) : options_(options) {}

  // std::nullopt when fewer than options.min_inliers correspondences agree on one transform.
  std::optional<Se3RansacResult> compute(const PinholeStereo& camera,
                                         const std::vector<Se3Correspondence>& correspondences) const;

 private:
  Se3RansacOptions options_;
};

}  // namespace heslam

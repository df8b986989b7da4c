// Camera pose from 3D-2D correspondences with outliers: RANSAC over minimal P3P samples (OpenCV AP3P),
// refined on the inliers. Seeded, so the same input and seed give the same pose bit for bit.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/geometry/pose.hpp"

namespace heslam {

struct PnpCorrespondence {
  Eigen::Vector3d p_w;
  double u_px = 0.0;
  double v_px = 0.0;
  double sigma2 = 1.0;  // variance of the keypoint position (its level scale squared)
};

struct PnpRansacOptions {
  int max_iterations = 300;       // ORB-SLAM2's relocalization PnP solver budget
  double probability = 0.99;      // stop when a better model is this unlikely to exist
  double chi2_threshold = 5.991;  // inlier: squared error / sigma2 below the 95 % 2-dof quantile
  int min_inliers = 10;           // fewer: no pose
  std::uint64_t seed = 1;
};

struct PnpRansacResult {
  Pose3 T_cw = Pose3::Identity();
  std::vector<bool> inlier;
  int inliers = 0;
  int iterations = 0;
};

class PnpRansac {
 public:
  explicit PnpRansac(const PnpRansacOptions& options = {}) : options_(options) {}

  // std::nullopt when fewer than options.min_inliers correspondences agree on one pose.
  std::optional<PnpRansacResult> compute(const PinholeStereo& camera,
                                         const std::vector<PnpCorrespondence>& correspondences) const;

 private:
  PnpRansacOptions options_;
};

}  // namespace heslam

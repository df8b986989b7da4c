// Re-fits a saved map (the mapper's STEM.map) with one more unknown: a residual radial distortion
// term k of the rectified images, shared by both cameras,
//   observed = principal point + f x (1 + k r^2),  r^2 = x^2 + y^2 (normalized rectified coordinates),
// the left keypoint at the point's bearing and the right one at its bearing from the right camera.
// It asks whether the map's own multi-view geometry says the lens model is off at the image's edges,
// without ground truth: the exposed-apart investigation traced the exposed-apart excess to peripheral stereo points and
// EuRoC's k1 (docs/benchmarks.md, "Cameras exposed apart", seventh and eighth passes).
//
// A diagnostic, not part of the pipeline: Ceres with automatic derivatives, all keyframes in the
// window free but the first, the ORB-SLAM2 Huber thresholds and the mapper's residual weights.
#pragma once

#include <vector>

#include "components/core/camera/pinhole_stereo.hpp"
#include "components/core/map/map.hpp"

namespace heslam::bench {

struct LensRefitOptions {
  // Keyframes taking part: those with stamp rank in [first, last) x (number of live keyframes).
  double first_fraction = 0.0;
  double last_fraction = 1.0;
  int max_iterations = 50;
  double disparity_sigma_ratio = 0.5;  // the mapper's default (local_mapper_options.hpp)
  // Step of k either side of the optimum for the curvature behind radial_k_sigma.
  double sigma_step = 0.002;
};

struct LensRefitResult {
  int keyframes = 0;
  int points = 0;  // live points with at least two observations in the window
  int observations = 0;
  int stereo_observations = 0;
  int skipped_observations = 0;  // naming a keypoint the keyframe does not have
  double cost_at_zero = 0.0;     // 0.5 sum of robustified whitened residuals, k fixed at 0
  double cost_free = 0.0;        // k estimated
  double radial_k = 0.0;
  // Standard deviation of radial_k from the cost's curvature, scaled by the residuals' measured
  // spread (reduced chi-square), so it does not depend on the assumed keypoint sigma.
  double radial_k_sigma = 0.0;
  double path_m_at_zero = 0.0;  // length of the keyframe path (stamp order) with k fixed at 0
  double path_m_free = 0.0;
};

struct LensRefitProfilePoint {
  double radial_k = 0.0;
  double cost = 0.0;
  double path_m = 0.0;
};

// Throws std::invalid_argument when the window holds fewer than two keyframes or no point.
LensRefitResult refit_residual_radial(const Map& map, const PinholeStereo& camera, const LensRefitOptions& options);

// The same fit with k held at each given value.
std::vector<LensRefitProfilePoint> refit_profile(const Map& map, const PinholeStereo& camera,
                                                 const LensRefitOptions& options, const std::vector<double>& radial_ks);

}  // namespace heslam::bench

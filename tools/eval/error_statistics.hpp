// Summary statistics of a list of errors, as evo reports them, and the rotation angle of a matrix.
//
// API:
//   ErrorStats s = compute_stats(errors);   // rmse, mean, median, std (population), min, max, sse
//   double angle = rotation_angle_rad(R);    // angle of the rotation R, in [0, pi]
#pragma once

#include <cstddef>
#include <span>

#include <Eigen/Core>

namespace heslam::eval {

struct ErrorStats {
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std = 0.0;  // population standard deviation (numpy's np.std)
  double min = 0.0;
  double max = 0.0;
  double sse = 0.0;  // sum of squared errors
  std::size_t count = 0;
};

// All zero for an empty list.
ErrorStats compute_stats(std::span<const double> errors);

// Robust for small angles (via the quaternion, not acos of the trace).
double rotation_angle_rad(const Eigen::Matrix3d& R);

}  // namespace heslam::eval

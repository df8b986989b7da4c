// Error statistics (evo's definitions) and rotation angles.
#include "tools/eval/error_statistics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

namespace heslam::eval {

ErrorStats compute_stats(std::span<const double> errors) {
  ErrorStats stats;
  stats.count = errors.size();
  if (errors.empty()) return stats;
  const double n = static_cast<double>(errors.size());
  double sum = 0.0;
  for (const double e : errors) {
    sum += e;
    stats.sse += e * e;
  }
  stats.mean = sum / n;
  stats.rmse = std::sqrt(stats.sse / n);
  double squared_deviation = 0.0;
  for (const double e : errors) squared_deviation += (e - stats.mean) * (e - stats.mean);
  stats.std = std::sqrt(squared_deviation / n);
  std::vector<double> sorted(errors.begin(), errors.end());
  std::sort(sorted.begin(), sorted.end());
  stats.min = sorted.front();
  stats.max = sorted.back();
  const std::size_t mid = sorted.size() / 2;
  stats.median = sorted.size() % 2 == 1 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
  return stats;
}

double rotation_angle_rad(const Eigen::Matrix3d& R) {
  return Eigen::AngleAxisd(Eigen::Quaterniond(R).normalized()).angle();
}

}  // namespace heslam::eval

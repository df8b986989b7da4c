// The equidistant (Kannala-Brandt) fisheye model, as Kalibr ("equidistant"), OpenCV's cv::fisheye,
// EuRoC / TUM-VI sensor.yaml and ORB-SLAM3 ("KannalaBrandt8") define it: a ray at angle theta from the
// optical axis lands at distance
//   theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
// from the principal point on the normalized image plane, in the ray's azimuth; the pixel is
// (fx x_d + cx, fy y_d + cy). Rays up to and beyond 90 degrees from the axis have a pixel.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Core>

namespace heslam {

// theta_d of a ray angle theta; k = k1 k2 k3 k4.
inline double equidistant_theta_d(double theta, const std::vector<double>& k) {
  const double t2 = theta * theta;
  return theta * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
}

// The ray angle theta whose theta_d is `theta_d` (Newton's method from theta = theta_d; the model is
// monotonic over the lens' field of view). Converges to ~1e-15 rad.
inline double equidistant_theta(double theta_d, const std::vector<double>& k) {
  double theta = theta_d;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const double t2 = theta * theta;
    const double slope = 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
    const double step = (equidistant_theta_d(theta, k) - theta_d) / slope;
    theta -= step;
    if (std::abs(step) < 1e-16) break;
  }
  return theta;
}

// Normalized distorted point (x_d, y_d) of the ray towards `p` (camera frame, p != 0).
inline Eigen::Vector2d equidistant_distort_ray(const Eigen::Vector3d& p, const std::vector<double>& k) {
  const double r = std::hypot(p.x(), p.y());
  if (r == 0.0) return Eigen::Vector2d::Zero();
  const double theta = std::atan2(r, p.z());
  return (equidistant_theta_d(theta, k) / r) * Eigen::Vector2d(p.x(), p.y());
}

// Unit ray of a normalized distorted point (x_d, y_d): the inverse of equidistant_distort_ray.
inline Eigen::Vector3d equidistant_undistort_ray(const Eigen::Vector2d& xy_d, const std::vector<double>& k) {
  const double theta_d = xy_d.norm();
  if (theta_d == 0.0) return Eigen::Vector3d::UnitZ();
  const double theta = equidistant_theta(theta_d, k);
  const Eigen::Vector2d azimuth = xy_d / theta_d;
  return {std::sin(theta) * azimuth.x(), std::sin(theta) * azimuth.y(), std::cos(theta)};
}

}  // namespace heslam

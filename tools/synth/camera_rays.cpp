// Ray tables, tiles and vignetting of a raw camera, with exact radial-tangential (un)distortion.
#include "tools/synth/camera_rays.hpp"

#include <algorithm>
#include <cmath>

#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "components/core/camera/equidistant.hpp"

namespace heslam::synth {
namespace {

constexpr int kNewtonIterations = 20;
constexpr double kNewtonTolerance = 1e-14;

// Every pixel of an equidistant lens looks less than kMaxFisheyeRayDeg off the axis, and theta_d grows
// with theta up to there (else two rays would share a pixel): checked at the farthest pixel's radius.
void check_fisheye_field_of_view(const CameraSpec& camera) {
  double theta_d_max = 0.0;
  for (const double c : {0.0, camera.width_px - 1.0}) {
    for (const double r : {0.0, camera.height_px - 1.0}) {
      theta_d_max =
          std::max(theta_d_max, std::hypot((c - camera.cx_px) / camera.fx_px, (r - camera.cy_px) / camera.fy_px));
    }
  }
  const std::vector<double>& k = camera.distortion;
  const double theta_max = CameraRays::kMaxFisheyeRayDeg * M_PI / 180.0;
  constexpr int kSteps = 1000;
  double previous = 0.0;
  for (int i = 1; i <= kSteps; ++i) {
    const double theta_d = heslam::equidistant_theta_d(theta_max * i / kSteps, k);
    if (theta_d <= previous) {
      throw std::runtime_error("camera.distortion: the equidistant lens is not monotonic below " +
                               std::to_string(CameraRays::kMaxFisheyeRayDeg) + " deg");
    }
    previous = theta_d;
  }
  if (theta_d_max >= previous) {
    throw std::runtime_error("camera: the equidistant lens sees " + std::to_string(CameraRays::kMaxFisheyeRayDeg) +
                             " deg or more off its axis in the image corners; the renderer needs less (a longer fx, "
                             "or a smaller image)");
  }
}

}  // namespace

Eigen::Vector2d distort_radtan(const Eigen::Vector2d& xy, const std::vector<double>& k) {
  if (k.size() < 4) return xy;
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + k[0] * r2 + k[1] * r2 * r2;
  return {x * radial + 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x),
          y * radial + k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y};
}

Eigen::Vector2d undistort_radtan(const Eigen::Vector2d& xy_distorted, const std::vector<double>& k) {
  if (k.size() < 4) return xy_distorted;
  Eigen::Vector2d xy = xy_distorted;
  for (int it = 0; it < kNewtonIterations; ++it) {
    const Eigen::Vector2d err = distort_radtan(xy, k) - xy_distorted;
    if (err.squaredNorm() < kNewtonTolerance * kNewtonTolerance) break;
    const double h = 1e-7;
    Eigen::Matrix2d J;
    J.col(0) =
        (distort_radtan(xy + Eigen::Vector2d(h, 0), k) - distort_radtan(xy - Eigen::Vector2d(h, 0), k)) / (2 * h);
    J.col(1) =
        (distort_radtan(xy + Eigen::Vector2d(0, h), k) - distort_radtan(xy - Eigen::Vector2d(0, h), k)) / (2 * h);
    xy -= J.inverse() * err;
  }
  return xy;
}

CameraRays::CameraRays(const CameraSpec& camera, bool apply_distortion)
    : camera_(camera),
      distorted_(apply_distortion && camera.distortion.size() >= 4),
      width_(camera.width_px),
      height_(camera.height_px) {
  const std::size_t n = static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  x_.resize(n);
  y_.resize(n);
  step_.resize(n);
  vignette_.assign(n, 1.0f);
  std::vector<double> no_distortion;
  const std::vector<double>& k = distorted_ ? camera.distortion : no_distortion;
  const bool fisheye = distorted_ && camera.lens == LensModel::kEquidistant;
  if (fisheye) check_fisheye_field_of_view(camera);
  for (int r = 0; r < height_; ++r) {
    for (int c = 0; c < width_; ++c) {
      const Eigen::Vector2d xd((c - camera.cx_px) / camera.fx_px, (r - camera.cy_px) / camera.fy_px);
      Eigen::Vector2d xu;
      if (fisheye) {
        const Eigen::Vector3d ray = equidistant_undistort_ray(xd, camera.distortion);
        xu = ray.head<2>() / ray.z();
      } else {
        xu = undistort_radtan(xd, k);
      }
      const std::size_t i =
          static_cast<std::size_t>(r) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(c);
      x_[i] = static_cast<float>(xu.x());
      y_[i] = static_cast<float>(xu.y());
    }
  }
  for (int r = 0; r < height_; ++r) {
    for (int c = 0; c < width_; ++c) {
      const int i = r * width_ + c;
      const int ic = c + 1 < width_ ? i + 1 : i - 1;
      const int ir = r + 1 < height_ ? i + width_ : i - width_;
      const float sx = std::hypot(x_[static_cast<std::size_t>(ic)] - x_[static_cast<std::size_t>(i)],
                                  y_[static_cast<std::size_t>(ic)] - y_[static_cast<std::size_t>(i)]);
      const float sy = std::hypot(x_[static_cast<std::size_t>(ir)] - x_[static_cast<std::size_t>(i)],
                                  y_[static_cast<std::size_t>(ir)] - y_[static_cast<std::size_t>(i)]);
      step_[static_cast<std::size_t>(i)] = std::max(sx, sy);
    }
  }
  x_min_ = *std::min_element(x_.begin(), x_.end());
  x_max_ = *std::max_element(x_.begin(), x_.end());
  y_min_ = *std::min_element(y_.begin(), y_.end());
  y_max_ = *std::max_element(y_.begin(), y_.end());
  for (int r0 = 0; r0 < height_; r0 += kTileSize) {
    for (int c0 = 0; c0 < width_; c0 += kTileSize) {
      Tile t{c0, r0, std::min(c0 + kTileSize, width_), std::min(r0 + kTileSize, height_), 1e9f, -1e9f, 1e9f, -1e9f};
      for (int r = t.r0; r < t.r1; ++r) {
        for (int c = t.c0; c < t.c1; ++c) {
          const std::size_t i = static_cast<std::size_t>(r * width_ + c);
          t.x_min = std::min(t.x_min, x_[i]);
          t.x_max = std::max(t.x_max, x_[i]);
          t.y_min = std::min(t.y_min, y_[i]);
          t.y_max = std::max(t.y_max, y_[i]);
        }
      }
      tiles_.push_back(t);
    }
  }
}

Eigen::Vector2f CameraRays::ray_at(float c, float r) const {
  const float cc = std::clamp(c, 0.0f, static_cast<float>(width_ - 1) - 1e-3f);
  const float rr = std::clamp(r, 0.0f, static_cast<float>(height_ - 1) - 1e-3f);
  const int c0 = static_cast<int>(cc), r0 = static_cast<int>(rr);
  const float fc = c - static_cast<float>(c0), fr = r - static_cast<float>(r0);  // extrapolates at borders
  const std::size_t i00 = static_cast<std::size_t>(r0 * width_ + c0);
  const std::size_t i01 = i00 + 1, i10 = i00 + static_cast<std::size_t>(width_), i11 = i10 + 1;
  const float x = (1 - fr) * ((1 - fc) * x_[i00] + fc * x_[i01]) + fr * ((1 - fc) * x_[i10] + fc * x_[i11]);
  const float y = (1 - fr) * ((1 - fc) * y_[i00] + fc * y_[i01]) + fr * ((1 - fc) * y_[i10] + fc * y_[i11]);
  return {x, y};
}

void CameraRays::set_vignetting(double corner_loss) {
  const double r_max2 = std::max({x_min_ * x_min_, x_max_ * x_max_}) + std::max({y_min_ * y_min_, y_max_ * y_max_});
  const double loss = std::clamp(corner_loss, 0.0, 0.95);
  // cos^4-like falloff 1 / (1 + k r^2)^2, with k chosen so the image corner loses `loss`.
  const double k = (1.0 / std::sqrt(1.0 - loss) - 1.0) / std::max(r_max2, 1e-9);
  for (std::size_t i = 0; i < vignette_.size(); ++i) {
    const double r2 = static_cast<double>(x_[i]) * x_[i] + static_cast<double>(y_[i]) * y_[i];
    const double g = 1.0 / (1.0 + k * r2);
    vignette_[i] = static_cast<float>(g * g);
  }
}

}  // namespace heslam::synth

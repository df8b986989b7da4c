// Per-pixel viewing rays of one raw camera, precomputed once: pixel (c, r) (OpenCV convention, integer
// = pixel centre) maps to the undistorted normalized ray (x, y, 1). With radial-tangential distortion
// the rendered image is the distorted one: each distorted pixel looks along its undistorted ray; so with
// an equidistant (fisheye) lens, whose every pixel must look less than kMaxFisheyeRayDeg off the axis.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "tools/synth/preset.hpp"

namespace heslam::synth {

// Radial-tangential distortion of a normalized point (k1 k2 p1 p2), as OpenCV and EuRoC define it.
Eigen::Vector2d distort_radtan(const Eigen::Vector2d& xy, const std::vector<double>& k);
// Inverse of distort_radtan by Newton iterations (converged to ~1e-12).
Eigen::Vector2d undistort_radtan(const Eigen::Vector2d& xy_distorted, const std::vector<double>& k);

class CameraRays {
 public:
  // The renderer intersects rays (x, y, 1): a fisheye pixel must see in front of the camera.
  static constexpr double kMaxFisheyeRayDeg = 85.0;

  static constexpr int kTileSize = 16;  // pixels; quads are culled against tiles' ray bounds

  struct Tile {
    int c0, r0, c1, r1;                // pixel range [c0, c1) x [r0, r1)
    float x_min, x_max, y_min, y_max;  // bounds of the normalized rays inside
  };

  // Throws std::runtime_error (one line) when an equidistant lens sees kMaxFisheyeRayDeg or more off its
  // axis, or is not monotonic, in some pixel.
  CameraRays(const CameraSpec& camera, bool apply_distortion);

  int width_px() const { return width_; }
  int height_px() const { return height_; }
  const CameraSpec& camera() const { return camera_; }
  bool distorted() const { return distorted_; }
  float x(int index) const { return x_[static_cast<std::size_t>(index)]; }
  float y(int index) const { return y_[static_cast<std::size_t>(index)]; }
  // Row-major arrays of x(i) and y(i), for loops over a row.
  const float* xs() const { return x_.data(); }
  const float* ys() const { return y_.data(); }
  const float* steps() const { return step_.data(); }
  // Normalized-plane distance between neighbouring pixels here (for texture footprints).
  float step(int index) const { return step_[static_cast<std::size_t>(index)]; }
  float vignetting_gain(int index) const { return vignette_[static_cast<std::size_t>(index)]; }
  const std::vector<Tile>& tiles() const { return tiles_; }
  float x_min() const { return x_min_; }
  float x_max() const { return x_max_; }
  float y_min() const { return y_min_; }
  float y_max() const { return y_max_; }

  // Ray of a sub-pixel position (bilinear in the table; exact for the pinhole model).
  Eigen::Vector2f ray_at(float c, float r) const;

  void set_vignetting(double corner_loss);

 private:
  CameraSpec camera_;
  bool distorted_ = false;
  int width_ = 0, height_ = 0;
  std::vector<float> x_, y_, step_, vignette_;
  std::vector<Tile> tiles_;
  float x_min_ = 0, x_max_ = 0, y_min_ = 0, y_max_ = 0;
};

}  // namespace heslam::synth

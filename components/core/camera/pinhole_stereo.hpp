// The rectified pinhole stereo model every algorithm after rectification works in.
//
// Both images share fx, fy, cx, cy and rows; the right camera sits baseline_m along +x of the left.
// A point at depth z in the left camera appears in the right image at u_right = u - bf / z.
#pragma once

#include <Eigen/Core>

namespace heslam {

struct PinholeStereo {
  double fx_px = 0.0;
  double fy_px = 0.0;
  double cx_px = 0.0;
  double cy_px = 0.0;
  double baseline_m = 0.0;
  int width_px = 0;
  int height_px = 0;

  // Focal length times baseline: disparity = bf / depth.
  double bf() const { return fx_px * baseline_m; }

  Eigen::Vector2d project(const Eigen::Vector3d& p_c) const {
    return {fx_px * p_c.x() / p_c.z() + cx_px, fy_px * p_c.y() / p_c.z() + cy_px};
  }
  double u_right(const Eigen::Vector3d& p_c) const { return project(p_c).x() - bf() / p_c.z(); }

  Eigen::Vector3d unproject(double u_px, double v_px, double depth_m) const {
    return {(u_px - cx_px) * depth_m / fx_px, (v_px - cy_px) * depth_m / fy_px, depth_m};
  }

  bool in_image(double u_px, double v_px) const {
    return u_px >= 0.0 && v_px >= 0.0 && u_px < width_px && v_px < height_px;
  }
};

}  // namespace heslam

// Dense depth of a rectified, equalized stereo pair with OpenCV's semi-global block matching, as a
// point cloud in the left camera's frame (x right, y down, z forward), thinned to one point per voxel
// of a lattice so that a keyframe's cloud is small enough to keep, persist and ray-cast again.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "components/core/camera/pinhole_stereo.hpp"

namespace heslam {

struct DenseStereoOptions {
  // cv::StereoSGBM: disparities searched (a multiple of 16), the matched block's side (odd), and the
  // smoothness penalties P1 / P2 per block pixel (OpenCV's recommended 8 and 32 x block^2).
  int num_disparities = 64;
  int block_size = 5;
  int uniqueness_ratio = 10;
  int speckle_window = 100;
  int speckle_range = 2;
  // Left-right consistency: the largest difference (pixels) between the left-right and right-left
  // matches; < 0 disables the check.
  int disp12_max_diff = 1;
  // Depth discontinuities: a pixel whose disparity differs by more than edge_step_px from one within
  // edge_radius_px is dropped (block matching smears a near surface over its far neighbours there,
  // and a point between the two lies on neither). 0 radius: kept.
  int edge_radius_px = 0;
  double edge_step_px = 1.0;
  // Smoothing: each kept disparity replaced by the mean of the kept ones within smooth_radius_px (after
  // the edge filter, so that with smooth_radius_px <= edge_radius_px no mean mixes two surfaces; on a
  // plane the mean of a symmetric window is the centre's value, the noise shrinks). 0: none.
  int smooth_radius_px = 0;
  // Sub-pixel refinement of SGBM's disparity (its parabola fit pixel-locks: ~0.3 px rms, biased, on the
  // synthetic room): per pixel a 1-D Lucas-Kanade on the pair, a (2 refine_radius_px + 1)^2 window, the
  // window's brightness offset removed, refine_iterations Gauss-Newton steps from SGBM's value. A pixel
  // whose refined value moved more than refine_max_change_px from SGBM's, or whose window's horizontal
  // gradient is too weak to fix it, is dropped. 0 iterations: SGBM's value is kept.
  // Both images are smoothed by a Gaussian of refine_prefilter_sigma_px first (0: not).
  int refine_iterations = 0;
  int refine_radius_px = 5;
  double refine_max_change_px = 1.0;
  double refine_prefilter_sigma_px = 1.0;
  // The disparity's sigma (pixels) on good texture: a point's depth sigma is z^2 / bf * this (the
  // fusion's hit / free rule, VoxelMapOptions::hit_max_sigma_m); 0: points taken as exact.
  double disparity_sigma_px = 0.0;
  // Depth range kept: stereo depth error grows with depth squared (z^2 / bf per pixel of disparity).
  double min_depth_m = 0.3;
  double max_depth_m = 5.0;
  // Every pixel_step-th pixel in both directions is turned into a point before thinning. 1: a surface
  // seen at a grazing angle (a floor, a box top, a wall along the path) still leaves a point in each
  // of its voxels; at 4 the points on it are ~12 cm apart at 2 m and the rays to them carve the voxels
  // between (room with true depth: seen-truth IoU 0.79 at 4, 0.98 at 1; docs/occupancy.md).
  int pixel_step = 1;
  // Thinning lattice (camera frame): one point (the mean) per cube of this side; 0: no thinning.
  double thin_voxel_m = 0.05;

  // Throws std::runtime_error naming `source` and the field when a value is out of range.
  void check(const std::string& source) const;
};

class DenseStereo {
 public:
  // Throws std::runtime_error when the options are unusable (check()).
  DenseStereo(const PinholeStereo& camera, const DenseStereoOptions& options);

  // The disparity image (CV_32F, pixels; < 0 where no match) of a rectified 8-bit pair of the camera's size.
  // Throws std::runtime_error when an image has another size or type.
  cv::Mat disparity(const cv::Mat& left, const cv::Mat& right) const;
  // The pair's points in the left camera's frame (metres), thinned; see the header comment.
  std::vector<Eigen::Vector3f> cloud(const cv::Mat& left, const cv::Mat& right) const;
  // The points of a disparity image (as disparity() returns).
  std::vector<Eigen::Vector3f> cloud_from_disparity(const cv::Mat& disparity) const;
  // The same points and, per point, the normal of its thinning cube's points (the covariance's
  // smallest axis, towards the camera; zero where the cube has fewer than 6 points or is not flat).
  void cloud_from_disparity(const cv::Mat& disparity, std::vector<Eigen::Vector3f>& points,
                            std::vector<Eigen::Vector3f>* normals) const;

  const PinholeStereo& camera() const { return camera_; }
  // disparity_sigma_px / bf (1/m): KeyframeCloud::sigma_per_m2 of this matcher's clouds.
  float sigma_per_m2() const { return static_cast<float>(options_.disparity_sigma_px / camera_.bf()); }

 private:
  PinholeStereo camera_;
  DenseStereoOptions options_;
};

}  // namespace heslam

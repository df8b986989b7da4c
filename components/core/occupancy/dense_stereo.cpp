// Dense stereo depth (see dense_stereo.hpp).
#include "components/core/occupancy/dense_stereo.hpp"

#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

#include <opencv2/calib3d.hpp>

namespace heslam {
namespace {

// OpenCV's recommended smoothness penalties per pixel of the block (cv::StereoSGBM documentation).
constexpr int kP1PerPixel = 8;
constexpr int kP2PerPixel = 32;
// StereoSGBM returns fixed-point disparities with 4 fractional bits.
constexpr double kDisparityScale = 16.0;

[[noreturn]] void fail(const std::string& source, const std::string& field, const std::string& expected) {
  throw std::runtime_error(source + ": " + field + " must be " + expected);
}

}  // namespace

void DenseStereoOptions::check(const std::string& source) const {
  if (num_disparities < 16 || num_disparities % 16 != 0) fail(source, "num_disparities", "a positive multiple of 16");
  if (block_size < 1 || block_size % 2 == 0 || block_size > 11) fail(source, "block_size", "odd, 1..11");
  if (!(min_depth_m > 0.0) || !(max_depth_m > min_depth_m) || !std::isfinite(max_depth_m)) {
    fail(source, "min_depth_m / max_depth_m", "0 < min < max, finite");
  }
  if (pixel_step < 1) fail(source, "pixel_step", ">= 1");
  if (!(thin_voxel_m >= 0.0) || !std::isfinite(thin_voxel_m)) fail(source, "thin_voxel_m", ">= 0");
  if (uniqueness_ratio < 0 || speckle_window < 0 || speckle_range < 0) {
    fail(source, "uniqueness_ratio / speckle_window / speckle_range", ">= 0");
  }
}

DenseStereo::DenseStereo(const PinholeStereo& camera, const DenseStereoOptions& options)
    : camera_(camera), options_(options) {
  options_.check("dense stereo options");
  if (!(camera.fx_px > 0.0) || !(camera.baseline_m > 0.0) || camera.width_px <= 0 || camera.height_px <= 0) {
    throw std::runtime_error("dense stereo: the rectified camera needs fx > 0, baseline > 0 and a size");
  }
}

cv::Mat DenseStereo::disparity(const cv::Mat& left, const cv::Mat& right) const {
  const cv::Size size(camera_.width_px, camera_.height_px);
  for (const cv::Mat* image : {&left, &right}) {
    if (image->size() != size || image->type() != CV_8UC1) {
      throw std::runtime_error("dense stereo: image of " + std::to_string(image->cols) + "x" +
                               std::to_string(image->rows) + " type " + std::to_string(image->type()) +
                               ", expected 8-bit grey " + std::to_string(size.width) + "x" +
                               std::to_string(size.height));
    }
  }
  const int area = options_.block_size * options_.block_size;
  cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
      0, options_.num_disparities, options_.block_size, kP1PerPixel * area, kP2PerPixel * area, 1, 0,
      options_.uniqueness_ratio, options_.speckle_window, options_.speckle_range, cv::StereoSGBM::MODE_SGBM);
  cv::Mat fixed;
  sgbm->compute(left, right, fixed);
  cv::Mat out;
  fixed.convertTo(out, CV_32F, 1.0 / kDisparityScale);
  return out;
}

std::vector<Eigen::Vector3f> DenseStereo::cloud_from_disparity(const cv::Mat& disparity) const {
  const double bf = camera_.bf();
  const int step = options_.pixel_step;
  // Thinning: mean of the points per lattice cube, in a sorted map so the output order is fixed.
  std::map<std::tuple<int, int, int>, std::pair<Eigen::Vector3d, int>> cubes;
  std::vector<Eigen::Vector3f> points;
  for (int v = 0; v < disparity.rows; v += step) {
    const float* row = disparity.ptr<float>(v);
    for (int u = 0; u < disparity.cols; u += step) {
      const double d = row[u];
      if (!(d > 0.0)) continue;
      const double z = bf / d;
      if (z < options_.min_depth_m || z > options_.max_depth_m) continue;
      const Eigen::Vector3d p = camera_.unproject(u, v, z);
      if (options_.thin_voxel_m <= 0.0) {
        points.push_back(p.cast<float>());
        continue;
      }
      const double r = options_.thin_voxel_m;
      // Zero-initialised: Eigen's default constructor leaves the sum undefined.
      auto& cube = cubes
                       .try_emplace({static_cast<int>(std::floor(p.x() / r)), static_cast<int>(std::floor(p.y() / r)),
                                     static_cast<int>(std::floor(p.z() / r))},
                                    Eigen::Vector3d::Zero(), 0)
                       .first->second;
      cube.first += p;
      ++cube.second;
    }
  }
  if (options_.thin_voxel_m <= 0.0) return points;
  points.reserve(cubes.size());
  for (const auto& [index, sum] : cubes) points.push_back((sum.first / sum.second).cast<float>());
  return points;
}

std::vector<Eigen::Vector3f> DenseStereo::cloud(const cv::Mat& left, const cv::Mat& right) const {
  return cloud_from_disparity(disparity(left, right));
}

}  // namespace heslam

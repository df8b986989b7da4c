// Dense stereo depth (see dense_stereo.hpp).
#include "components/core/occupancy/dense_stereo.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Eigenvalues>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace heslam {
namespace {

// OpenCV's recommended smoothness penalties per pixel of the block (cv::StereoSGBM documentation).
constexpr int kP1PerPixel = 8;
constexpr int kP2PerPixel = 32;
// StereoSGBM returns fixed-point disparities with 4 fractional bits.
constexpr double kDisparityScale = 16.0;
// Thinning cubes packed 21 bits per axis (+-2^20 cubes: +-52 km at 5 cm).
constexpr int kCubeBits = 21;
constexpr double kCubeOffset = static_cast<double>(1 << (kCubeBits - 1));
constexpr std::uint64_t kCubeMask = (std::uint64_t{1} << kCubeBits) - 1;
// A cube's normal: from at least this many points, and only when flat (smallest spread below this
// fraction of the middle one).
constexpr std::size_t kMinNormalPoints = 6;
constexpr double kMaxFlatness = 0.2;

// Sub-pixel refinement: a window's horizontal gradient must have at least this variance (grey levels^2
// per pixel^2) for its disparity to be fixed by it; weaker texture keeps no disparity.
constexpr float kRefineMinGradientVariance = 1.0f;
// At most this change per Gauss-Newton step (pixels): beyond it the linearization does not hold.
constexpr float kRefineMaxStepPx = 0.5f;

// The sum over each pixel's (2 radius + 1)^2 window (zero outside the image).
cv::Mat window_sum(const cv::Mat& values, int radius) {
  cv::Mat sum;
  const int side = 2 * radius + 1;
  cv::boxFilter(values, sum, CV_32F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  return sum;
}

// Refines `disparity` (CV_32F, <= 0: none) in place by 1-D Lucas-Kanade on the pair: each pixel's left
// grey value against the right image at u - d (linear interpolation along the row), the residual's and the
// right gradient's window means removed (a brightness offset between the cameras), one Gauss-Newton step
// per iteration for all pixels at once (a window's pixels are sampled at their own disparities, so a
// smooth surface converges as one). Both images are smoothed by a Gaussian of prefilter_sigma px first
// when > 0 (linear interpolation of texture near the sampling limit pulls the estimate to whole pixels).
// Pixels that move more than max_change from SGBM's value or have too little gradient are dropped.
void refine_disparity(cv::Mat& disparity, const cv::Mat& left_u8, const cv::Mat& right_u8, int iterations, int radius,
                      double max_change, double prefilter_sigma) {
  cv::Mat left, right;
  left_u8.convertTo(left, CV_32F);
  right_u8.convertTo(right, CV_32F);
  if (prefilter_sigma > 0.0) {
    cv::GaussianBlur(left, left, cv::Size(0, 0), prefilter_sigma);
    cv::GaussianBlur(right, right, cv::Size(0, 0), prefilter_sigma);
  }
  cv::Mat gradient(right.size(), CV_32F, cv::Scalar(0.f));
  for (int v = 0; v < right.rows; ++v) {
    const float* r = right.ptr<float>(v);
    float* g = gradient.ptr<float>(v);
    for (int u = 1; u + 1 < right.cols; ++u) g[u] = 0.5f * (r[u + 1] - r[u - 1]);
  }
  const cv::Mat sgbm = disparity.clone();
  const int rows = disparity.rows, cols = disparity.cols;
  cv::Mat w(disparity.size(), CV_32F), e(disparity.size(), CV_32F), g(disparity.size(), CV_32F);
  cv::Mat eg(disparity.size(), CV_32F), gg(disparity.size(), CV_32F);
  cv::Mat sw, se, sg, seg, sgg;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    for (int v = 0; v < rows; ++v) {
      const float* d = disparity.ptr<float>(v);
      const float* l = left.ptr<float>(v);
      const float* r = right.ptr<float>(v);
      const float* gr = gradient.ptr<float>(v);
      float *pw = w.ptr<float>(v), *pe = e.ptr<float>(v), *pg = g.ptr<float>(v);
      float *peg = eg.ptr<float>(v), *pgg = gg.ptr<float>(v);
      for (int u = 0; u < cols; ++u) {
        const float x = static_cast<float>(u) - d[u];
        if (!(d[u] > 0.f) || !(x >= 1.f) || !(x < static_cast<float>(cols - 2))) {
          pw[u] = pe[u] = pg[u] = peg[u] = pgg[u] = 0.f;
          continue;
        }
        const int i = static_cast<int>(x);
        const float a = x - static_cast<float>(i);
        const float residual = l[u] - (r[i] + a * (r[i + 1] - r[i]));
        const float slope = gr[i] + a * (gr[i + 1] - gr[i]);
        pw[u] = 1.f;
        pe[u] = residual;
        pg[u] = slope;
        peg[u] = residual * slope;
        pgg[u] = slope * slope;
      }
    }
    sw = window_sum(w, radius);
    se = window_sum(e, radius);
    sg = window_sum(g, radius);
    seg = window_sum(eg, radius);
    sgg = window_sum(gg, radius);
    for (int v = 0; v < rows; ++v) {
      float* d = disparity.ptr<float>(v);
      const float *n = sw.ptr<float>(v), *s_e = se.ptr<float>(v), *s_g = sg.ptr<float>(v);
      const float *s_eg = seg.ptr<float>(v), *s_gg = sgg.ptr<float>(v);
      for (int u = 0; u < cols; ++u) {
        if (!(d[u] > 0.f) || n[u] < 1.f) continue;
        const float covariance = s_eg[u] - s_e[u] * s_g[u] / n[u];
        const float variance = s_gg[u] - s_g[u] * s_g[u] / n[u];
        if (!(variance > kRefineMinGradientVariance * n[u])) continue;
        // L(u) = R(u - d) + c: d + delta lowers the residual by delta * gradient.
        d[u] += std::clamp(-covariance / variance, -kRefineMaxStepPx, kRefineMaxStepPx);
      }
    }
  }
  // The last step's window statistics decide which pixels keep their disparity.
  for (int v = 0; v < rows; ++v) {
    float* d = disparity.ptr<float>(v);
    const float* d0 = sgbm.ptr<float>(v);
    const float *n = sw.ptr<float>(v), *s_g = sg.ptr<float>(v), *s_gg = sgg.ptr<float>(v);
    for (int u = 0; u < cols; ++u) {
      if (!(d0[u] > 0.f)) continue;
      const bool textured = n[u] >= 1.f && s_gg[u] - s_g[u] * s_g[u] / n[u] > kRefineMinGradientVariance * n[u];
      if (!textured || !(std::abs(d[u] - d0[u]) <= max_change) || !(d[u] > 0.f)) d[u] = -1.f;
    }
  }
}

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
  if (edge_radius_px < 0 || edge_radius_px > 16) fail(source, "edge_radius_px", "0..16");
  if (smooth_radius_px < 0 || smooth_radius_px > 16) fail(source, "smooth_radius_px", "0..16");
  if (!(edge_step_px > 0.0) || !std::isfinite(edge_step_px)) fail(source, "edge_step_px", "> 0");
  if (refine_iterations < 0 || refine_iterations > 32) fail(source, "refine_iterations", "0..32");
  if (refine_radius_px < 1 || refine_radius_px > 16) fail(source, "refine_radius_px", "1..16");
  if (!(refine_max_change_px > 0.0) || !std::isfinite(refine_max_change_px)) {
    fail(source, "refine_max_change_px", "> 0");
  }
  if (!(refine_prefilter_sigma_px >= 0.0) || refine_prefilter_sigma_px > 8.0) {
    fail(source, "refine_prefilter_sigma_px", "0..8");
  }
  if (!(disparity_sigma_px >= 0.0) || !std::isfinite(disparity_sigma_px)) fail(source, "disparity_sigma_px", ">= 0");
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
  cv::Ptr<cv::StereoSGBM> sgbm =
      cv::StereoSGBM::create(0, options_.num_disparities, options_.block_size, kP1PerPixel * area, kP2PerPixel * area,
                             options_.disp12_max_diff, 0, options_.uniqueness_ratio, options_.speckle_window,
                             options_.speckle_range, cv::StereoSGBM::MODE_SGBM);
  cv::Mat fixed;
  sgbm->compute(left, right, fixed);
  cv::Mat out;
  fixed.convertTo(out, CV_32F, 1.0 / kDisparityScale);
  if (options_.refine_iterations > 0) {
    refine_disparity(out, left, right, options_.refine_iterations, options_.refine_radius_px,
                     options_.refine_max_change_px, options_.refine_prefilter_sigma_px);
  }
  if (options_.edge_radius_px > 0) {
    // The largest and smallest valid disparity around each pixel (invalid pixels count for neither).
    const int side = 2 * options_.edge_radius_px + 1;
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(side, side));
    const cv::Mat invalid = out <= 0.f;
    cv::Mat high, low = out.clone();
    low.setTo(std::numeric_limits<float>::max(), invalid);
    cv::dilate(out, high, kernel);
    cv::erode(low, low, kernel);
    const float step = static_cast<float>(options_.edge_step_px);
    for (int v = 0; v < out.rows; ++v) {
      float* row = out.ptr<float>(v);
      const float* h = high.ptr<float>(v);
      const float* l = low.ptr<float>(v);
      for (int u = 0; u < out.cols; ++u) {
        if (row[u] > 0.f && (h[u] - row[u] > step || row[u] - l[u] > step)) row[u] = -1.f;
      }
    }
  }
  if (options_.smooth_radius_px > 0) {
    const int side = 2 * options_.smooth_radius_px + 1;
    cv::Mat valid, sum, count;
    cv::threshold(out, valid, 0.0, 1.0, cv::THRESH_BINARY);  // 1 where kept, 0 elsewhere
    cv::boxFilter(out.mul(valid), sum, CV_32F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
    cv::boxFilter(valid, count, CV_32F, cv::Size(side, side), cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
    for (int v = 0; v < out.rows; ++v) {
      float* row = out.ptr<float>(v);
      const float* s = sum.ptr<float>(v);
      const float* c = count.ptr<float>(v);
      for (int u = 0; u < out.cols; ++u) {
        if (row[u] > 0.f) row[u] = s[u] / c[u];
      }
    }
  }
  return out;
}

std::vector<Eigen::Vector3f> DenseStereo::cloud_from_disparity(const cv::Mat& disparity) const {
  std::vector<Eigen::Vector3f> points;
  cloud_from_disparity(disparity, points, nullptr);
  return points;
}

void DenseStereo::cloud_from_disparity(const cv::Mat& disparity, std::vector<Eigen::Vector3f>& points,
                                       std::vector<Eigen::Vector3f>* normals) const {
  points.clear();
  if (normals) normals->clear();
  const double bf = camera_.bf();
  const int step = options_.pixel_step;
  const double r = options_.thin_voxel_m;
  // Thinning: the points keyed by their lattice cube (x, y, z packed most significant first, so the
  // key order is the cubes' lexicographic order and the output order is fixed), sorted, one mean per cube.
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> keyed;
  auto axis = [](double value) { return static_cast<std::uint64_t>(std::floor(value) + kCubeOffset) & kCubeMask; };
  // The left num_disparities columns: their match may lie left of the right image, where SGBM
  // still answers with a smaller (wrong) disparity, i.e. a point too far.
  const int first_column = options_.num_disparities;
  for (int v = 0; v < disparity.rows; v += step) {
    const float* row = disparity.ptr<float>(v);
    for (int u = first_column; u < disparity.cols; u += step) {
      const double d = row[u];
      if (!(d > 0.0)) continue;
      const double z = bf / d;
      if (z < options_.min_depth_m || z > options_.max_depth_m) continue;
      const Eigen::Vector3d p = camera_.unproject(u, v, z);
      if (r <= 0.0) {
        points.push_back(p.cast<float>());
        if (normals) normals->push_back(Eigen::Vector3f::Zero());
        continue;
      }
      keyed.emplace_back((axis(p.x() / r) << (2 * kCubeBits)) | (axis(p.y() / r) << kCubeBits) | axis(p.z() / r), p);
    }
  }
  if (r <= 0.0) return;
  std::stable_sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t begin = 0; begin < keyed.size();) {
    std::size_t end = begin;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (; end < keyed.size() && keyed[end].first == keyed[begin].first; ++end) sum += keyed[end].second;
    const std::size_t n = end - begin;
    const Eigen::Vector3d mean = sum / static_cast<double>(n);
    points.push_back(mean.cast<float>());
    if (normals) {
      Eigen::Vector3f normal = Eigen::Vector3f::Zero();
      if (n >= kMinNormalPoints) {
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        for (std::size_t i = begin; i < end; ++i) {
          const Eigen::Vector3d d = keyed[i].second - mean;
          covariance += d * d.transpose();
        }
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
        const Eigen::Vector3d values = eigen.eigenvalues();  // ascending
        if (eigen.info() == Eigen::Success && values(0) < kMaxFlatness * values(1)) {
          Eigen::Vector3d axis = eigen.eigenvectors().col(0);
          if (axis.dot(mean) > 0.0) axis = -axis;  // towards the camera
          normal = axis.cast<float>();
        }
      }
      normals->push_back(normal);
    }
    begin = end;
  }
}

std::vector<Eigen::Vector3f> DenseStereo::cloud(const cv::Mat& left, const cv::Mat& right) const {
  return cloud_from_disparity(disparity(left, right));
}

}  // namespace heslam

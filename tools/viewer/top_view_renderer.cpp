// Orthographic top view of the map (see top_view_renderer.hpp).
#include "tools/viewer/top_view_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "tools/viewer/colours.hpp"

namespace heslam::viewer {
namespace {

// The view fits the 2nd..98th percentile of the points (a few far outliers must not shrink the map
// to a dot) and everything else entirely, plus a margin.
constexpr double kPointPercentile = 0.02;
constexpr int kMarginPx = 30;
// Smallest extent shown, so a still camera at the start is not magnified into noise.
constexpr double kMinExtentM = 0.5;
// Frustum depth as a fraction of the shown extent (readable at any map size).
constexpr double kFrustumFraction = 0.025;
constexpr int kLegendTopPx = 18;

class Projection {
 public:
  Projection(double min_x, double max_x, double min_z, double max_z, cv::Size size) {
    const double extent_x = std::max(max_x - min_x, kMinExtentM);
    const double extent_z = std::max(max_z - min_z, kMinExtentM);
    scale_ =
        std::min((size.width - 2.0 * kMarginPx) / extent_x, (size.height - 2.0 * kMarginPx - kLegendTopPx) / extent_z);
    centre_x_ = 0.5 * (min_x + max_x);
    centre_z_ = 0.5 * (min_z + max_z);
    size_ = size;
    extent_m_ = std::max(extent_x, extent_z);
  }
  cv::Point operator()(const Eigen::Vector3d& p_w) const {
    return {static_cast<int>(std::lround(size_.width / 2.0 + (p_w.x() - centre_x_) * scale_)),
            static_cast<int>(std::lround((size_.height + kLegendTopPx) / 2.0 - (p_w.z() - centre_z_) * scale_))};
  }
  double extent_m() const { return extent_m_; }
  double scale() const { return scale_; }

 private:
  double scale_ = 1.0, centre_x_ = 0.0, centre_z_ = 0.0, extent_m_ = 1.0;
  cv::Size size_;
};

Projection fit(const Scene& scene, const Layers& layers, cv::Size size) {
  std::vector<double> xs, zs;
  for (const ScenePoint& point : scene.points) {
    xs.push_back(point.p_w.x());
    zs.push_back(point.p_w.z());
  }
  double min_x = 0.0, max_x = 0.0, min_z = 0.0, max_z = 0.0;
  bool any = false;
  auto include = [&](double x, double z) {
    if (!std::isfinite(x) || !std::isfinite(z)) return;
    min_x = any ? std::min(min_x, x) : x;
    max_x = any ? std::max(max_x, x) : x;
    min_z = any ? std::min(min_z, z) : z;
    max_z = any ? std::max(max_z, z) : z;
    any = true;
  };
  if (!xs.empty()) {
    const auto low = static_cast<std::ptrdiff_t>(kPointPercentile * static_cast<double>(xs.size()));
    const auto high = static_cast<std::ptrdiff_t>(xs.size()) - 1 - low;
    std::nth_element(xs.begin(), xs.begin() + low, xs.end());
    const double x_low = xs[static_cast<std::size_t>(low)];
    std::nth_element(xs.begin(), xs.begin() + high, xs.end());
    const double x_high = xs[static_cast<std::size_t>(high)];
    std::nth_element(zs.begin(), zs.begin() + low, zs.end());
    const double z_low = zs[static_cast<std::size_t>(low)];
    std::nth_element(zs.begin(), zs.begin() + high, zs.end());
    const double z_high = zs[static_cast<std::size_t>(high)];
    include(x_low, z_low);
    include(x_high, z_high);
  }
  for (const Pose3& T_wc : scene.keyframes_T_wc) include(T_wc.translation().x(), T_wc.translation().z());
  for (const Eigen::Vector3d& p : scene.trajectory_w) include(p.x(), p.z());
  if (layers.ground_truth) {
    for (const Eigen::Vector3d& p : scene.ground_truth_w) include(p.x(), p.z());
  }
  if (scene.has_camera) include(scene.current_T_wc.translation().x(), scene.current_T_wc.translation().z());
  return Projection(min_x, max_x, min_z, max_z, size);
}

// A camera frustum: centre to the four image corners at `depth_m`, and the image rectangle.
void draw_frustum(cv::Mat& image, const Projection& project, const Pose3& T_wc, const PinholeStereo& camera,
                  double depth_m, const cv::Scalar& colour, int thickness) {
  const double half_w = camera.fx_px > 0.0 ? 0.5 * camera.width_px / camera.fx_px : 0.6;
  const double half_h = camera.fy_px > 0.0 ? 0.5 * camera.height_px / camera.fy_px : 0.4;
  const cv::Point centre = project(T_wc.translation());
  cv::Point corners[4];
  const double signs[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (int i = 0; i < 4; ++i) {
    corners[i] =
        project(T_wc * Eigen::Vector3d(signs[i][0] * half_w * depth_m, signs[i][1] * half_h * depth_m, depth_m));
    cv::line(image, centre, corners[i], colour, thickness, cv::LINE_8);
  }
  for (int i = 0; i < 4; ++i) cv::line(image, corners[i], corners[(i + 1) % 4], colour, thickness, cv::LINE_8);
}

void draw_polyline(cv::Mat& image, const Projection& project, const std::vector<Eigen::Vector3d>& points,
                   const cv::Scalar& colour) {
  for (std::size_t i = 1; i < points.size(); ++i) {
    cv::line(image, project(points[i - 1]), project(points[i]), colour, 1, cv::LINE_AA);
  }
}

}  // namespace

TopView TopViewRenderer::render(const Scene& scene, const Layers& layers) const {
  TopView view;
  view.image = cv::Mat(size_, CV_8UC3, colours::kBackground);
  cv::Mat& image = view.image;
  const Projection project = fit(scene, layers, size_);
  const double frustum_m = kFrustumFraction * project.extent_m();

  if (layers.points) {
    // Culled first, so live points are drawn over them.
    for (int pass = 0; pass < 2; ++pass) {
      for (const ScenePoint& point : scene.points) {
        const bool culled = point.category == PointCategory::kCulled;
        if (culled != (pass == 0) || (culled && !layers.culled_points)) continue;
        const cv::Point p = project(point.p_w);
        if (p.x < 0 || p.y < 0 || p.x >= image.cols || p.y >= image.rows) continue;
        cv::circle(image, p, 1, colours::of(point.category), cv::FILLED, cv::LINE_8);
        ++view.points_drawn;
      }
    }
  }
  if (layers.covisibility) {
    for (const SceneEdge& edge : scene.covisibility) {
      cv::line(image, project(edge.from_w), project(edge.to_w), colours::kCovisibility, 1, cv::LINE_AA);
    }
  }
  if (layers.spanning_tree) {
    for (const SceneEdge& edge : scene.spanning_tree) {
      cv::line(image, project(edge.from_w), project(edge.to_w), colours::kSpanningTree, 1, cv::LINE_AA);
    }
  }
  if (layers.ground_truth) draw_polyline(image, project, scene.ground_truth_w, colours::kGroundTruth);
  if (layers.trajectory) draw_polyline(image, project, scene.trajectory_w, colours::kTrajectory);
  if (layers.keyframes) {
    for (const Pose3& T_wc : scene.keyframes_T_wc) {
      draw_frustum(image, project, T_wc, scene.camera, frustum_m, colours::kKeyframe, 1);
      ++view.frustums_drawn;
    }
  }
  if (scene.has_camera)
    draw_frustum(image, project, scene.current_T_wc, scene.camera, 2.0 * frustum_m, colours::kCurrentCamera, 2);

  const std::string legend = "top view (x right, z up)  " + std::to_string(scene.map_keyframes) + " keyframes  " +
                             std::to_string(scene.map_points) + " points  " + std::to_string(scene.loop_corrections) +
                             " loop corrections  scale " + std::to_string(static_cast<int>(project.scale())) + " px/m";
  cv::putText(image, legend, {8, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.45, colours::kText, 1, cv::LINE_AA);
  return view;
}

}  // namespace heslam::viewer

// Orthographic top view of the map (see top_view_renderer.hpp).
#include "tools/viewer/top_view_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "tools/viewer/colours.hpp"

namespace heslam::viewer {
namespace {

// The map fit takes the 2nd..98th percentile of the points (a few far outliers must not shrink the
// map to a dot) and everything else entirely, plus a margin.
constexpr double kPointPercentile = 0.02;
constexpr int kMarginPx = 30;
// Smallest extent shown, so a still camera at the start is not magnified into noise.
constexpr double kMinExtentM = 0.5;
// Frustum depth as a fraction of the shown extent (readable at any map size).
constexpr double kFrustumFraction = 0.025;
constexpr int kLegendTopPx = 18;
// Room below the fitted area for the scale bar and its label.
constexpr int kScaleBarRoomPx = 24;
// The grid step is the smallest round step whose cells are at least this wide (about 6..15 cells
// across the default 900-pixel picture).
constexpr double kMinGridCellPx = 60.0;
// Line widths readable at the default size: the ground truth wider, under the estimate, so both show
// where they overlap.
constexpr int kTrajectoryThicknessPx = 2;
constexpr int kGroundTruthThicknessPx = 5;
constexpr int kScaleBarThicknessPx = 3;
constexpr int kAxisLengthPx = 36;

class Projection {
 public:
  Projection(double min_x, double max_x, double min_z, double max_z, cv::Size size) {
    const double extent_x = std::max(max_x - min_x, kMinExtentM);
    const double extent_z = std::max(max_z - min_z, kMinExtentM);
    const double fitted_height = size.height - 2.0 * kMarginPx - kLegendTopPx - kScaleBarRoomPx;
    scale_ = std::min((size.width - 2.0 * kMarginPx) / extent_x, fitted_height / extent_z);
    centre_x_ = 0.5 * (min_x + max_x);
    centre_z_ = 0.5 * (min_z + max_z);
    centre_row_px_ = kLegendTopPx + kMarginPx + 0.5 * fitted_height;
    size_ = size;
    extent_m_ = std::max(extent_x, extent_z);
  }
  cv::Point operator()(const Eigen::Vector3d& p_w) const { return pixel(p_w.x(), p_w.z()); }
  cv::Point pixel(double x_m, double z_m) const {
    return {static_cast<int>(std::lround(column(x_m))), static_cast<int>(std::lround(row(z_m)))};
  }
  double column(double x_m) const { return size_.width / 2.0 + (x_m - centre_x_) * scale_; }
  double row(double z_m) const { return centre_row_px_ - (z_m - centre_z_) * scale_; }
  // The world x / z at a pixel column / row.
  double x_at(double column_px) const { return centre_x_ + (column_px - size_.width / 2.0) / scale_; }
  double z_at(double row_px) const { return centre_z_ - (row_px - centre_row_px_) / scale_; }
  double extent_m() const { return extent_m_; }
  double scale() const { return scale_; }

 private:
  double scale_ = 1.0, centre_x_ = 0.0, centre_z_ = 0.0, centre_row_px_ = 0.0, extent_m_ = 1.0;
  cv::Size size_;
};

class Bounds {
 public:
  void include(double x, double z) {
    if (!std::isfinite(x) || !std::isfinite(z)) return;
    min_x_ = any_ ? std::min(min_x_, x) : x;
    max_x_ = any_ ? std::max(max_x_, x) : x;
    min_z_ = any_ ? std::min(min_z_, z) : z;
    max_z_ = any_ ? std::max(max_z_, z) : z;
    any_ = true;
  }
  void include(const Eigen::Vector3d& p_w) { include(p_w.x(), p_w.z()); }
  bool any() const { return any_; }
  Projection projection(cv::Size size) const { return Projection(min_x_, max_x_, min_z_, max_z_, size); }

 private:
  double min_x_ = 0.0, max_x_ = 0.0, min_z_ = 0.0, max_z_ = 0.0;
  bool any_ = false;
};

void include_map(const Scene& scene, Bounds& bounds) {
  std::vector<double> xs, zs;
  for (const ScenePoint& point : scene.points) {
    xs.push_back(point.p_w.x());
    zs.push_back(point.p_w.z());
  }
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
    bounds.include(x_low, z_low);
    bounds.include(x_high, z_high);
  }
  for (const Pose3& T_wc : scene.keyframes_T_wc) bounds.include(T_wc.translation());
}

Projection fit(const Scene& scene, const Layers& layers, TopViewFit mode, cv::Size size) {
  Bounds bounds;
  for (const Eigen::Vector3d& p : scene.trajectory_w) bounds.include(p);
  if (layers.ground_truth) {
    for (const Eigen::Vector3d& p : scene.ground_truth_w) bounds.include(p);
  }
  if (scene.has_camera) bounds.include(scene.current_T_wc.translation());
  // Before any trajectory arrived (a viewer that joined a finished run), the map is all there is.
  if (mode == TopViewFit::kMap || scene.trajectory_w.empty()) include_map(scene, bounds);
  return bounds.projection(size);
}

// The smallest of 1, 2, 5 x 10^k m whose cells are at least kMinGridCellPx wide.
double grid_step_m(double scale_px_per_m) {
  const double min_step_m = kMinGridCellPx / scale_px_per_m;
  const double decade = std::pow(10.0, std::floor(std::log10(min_step_m)));
  for (const double factor : {1.0, 2.0, 5.0, 10.0}) {
    if (factor * decade >= min_step_m) return factor * decade;
  }
  return 10.0 * decade;
}

std::string format_length(double metres) {
  char text[32];
  if (metres >= 1.0) {
    std::snprintf(text, sizeof text, "%g m", metres);
  } else if (metres >= 0.01) {
    std::snprintf(text, sizeof text, "%g cm", metres * 100.0);
  } else {
    std::snprintf(text, sizeof text, "%g mm", metres * 1000.0);
  }
  return text;
}

// Grid lines at multiples of the step (world-anchored, so they stay put while the view grows).
void draw_grid(cv::Mat& image, const Projection& project, double step_m) {
  const double first_x = std::ceil(project.x_at(0) / step_m) * step_m;
  for (double x = first_x; project.column(x) < image.cols; x += step_m) {
    const int column = static_cast<int>(std::lround(project.column(x)));
    cv::line(image, {column, kLegendTopPx + 4}, {column, image.rows - 1}, colours::kGrid, 1, cv::LINE_8);
  }
  const double first_z = std::ceil(project.z_at(image.rows - 1) / step_m) * step_m;
  for (double z = first_z; project.row(z) > kLegendTopPx + 4; z += step_m) {
    const int row = static_cast<int>(std::lround(project.row(z)));
    cv::line(image, {0, row}, {image.cols - 1, row}, colours::kGrid, 1, cv::LINE_8);
  }
}

// Bottom left: a bar one grid step long, labelled with its length.
void draw_scale_bar(cv::Mat& image, double step_m, double scale_px_per_m) {
  const int length_px = static_cast<int>(std::lround(step_m * scale_px_per_m));
  const int row = image.rows - 10;
  const cv::Point start(kMarginPx, row), end(kMarginPx + length_px, row);
  // A filled rectangle, not a thick line (whose round caps would lengthen it): exactly length_px + 1 wide.
  cv::rectangle(image, start - cv::Point(0, kScaleBarThicknessPx / 2), end + cv::Point(0, kScaleBarThicknessPx / 2),
                colours::kScaleBar, cv::FILLED, cv::LINE_8);
  cv::line(image, start - cv::Point(0, 5), start + cv::Point(0, 3), colours::kScaleBar, 1, cv::LINE_8);
  cv::line(image, end - cv::Point(0, 5), end + cv::Point(0, 3), colours::kScaleBar, 1, cv::LINE_8);
  cv::putText(image, format_length(step_m) + " (grid step)", {end.x + 8, row + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45,
              colours::kText, 1, cv::LINE_AA);
}

// Bottom right: the directions of the picture's axes.
void draw_axes(cv::Mat& image) {
  const cv::Point origin(image.cols - kMarginPx - kAxisLengthPx, image.rows - 10);
  cv::arrowedLine(image, origin, origin + cv::Point(kAxisLengthPx, 0), colours::kAxisX, 2, cv::LINE_8, 0, 0.25);
  cv::arrowedLine(image, origin, origin - cv::Point(0, kAxisLengthPx), colours::kAxisZ, 2, cv::LINE_8, 0, 0.25);
  cv::putText(image, "x", origin + cv::Point(kAxisLengthPx - 8, -6), cv::FONT_HERSHEY_SIMPLEX, 0.45, colours::kAxisX, 1,
              cv::LINE_AA);
  cv::putText(image, "z", origin + cv::Point(6, -kAxisLengthPx + 8), cv::FONT_HERSHEY_SIMPLEX, 0.45, colours::kAxisZ, 1,
              cv::LINE_AA);
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
                   const cv::Scalar& colour, int thickness) {
  for (std::size_t i = 1; i < points.size(); ++i) {
    // LINE_8: the line's pixels keep its exact colour (a picture can be checked for it).
    cv::line(image, project(points[i - 1]), project(points[i]), colour, thickness, cv::LINE_8);
  }
}

// Each known cell of the grid as the quadrilateral its corners project to (a square when the grid's
// up is the world's -y, as without an IMU). Returns the cells drawn.
std::size_t draw_occupancy(cv::Mat& image, const Projection& project, const OccupancyGrid& grid, const Pose3& T_wg) {
  const double r = grid.resolution_m();
  const cv::Rect frame(0, 0, image.cols, image.rows);
  std::size_t drawn = 0;
  for (const auto& [index, state] : grid.cells()) {
    if (state == CellState::kUnknown) continue;
    const double x = index.first * r, y = index.second * r;
    cv::Point corners[4] = {project(T_wg * Eigen::Vector3d(x, y, 0.0)), project(T_wg * Eigen::Vector3d(x + r, y, 0.0)),
                            project(T_wg * Eigen::Vector3d(x + r, y + r, 0.0)),
                            project(T_wg * Eigen::Vector3d(x, y + r, 0.0))};
    const cv::Rect box = cv::boundingRect(std::vector<cv::Point>(corners, corners + 4));
    if ((box & frame).empty() && !frame.contains(corners[0])) continue;
    cv::fillConvexPoly(image, corners, 4, state == CellState::kOccupied ? colours::kOccupiedCell : colours::kFreeCell,
                       cv::LINE_8);
    ++drawn;
  }
  return drawn;
}

}  // namespace

TopView TopViewRenderer::render(const Scene& scene, const Layers& layers) const {
  TopView view;
  view.image = cv::Mat(size_, CV_8UC3, colours::kBackground);
  cv::Mat& image = view.image;
  const Projection project = fit(scene, layers, fit_, size_);
  const double frustum_m = kFrustumFraction * project.extent_m();
  view.scale_px_per_m = project.scale();
  view.grid_step_m = grid_step_m(project.scale());
  if (layers.occupancy && scene.occupancy) {
    view.occupancy_cells_drawn = draw_occupancy(image, project, *scene.occupancy, scene.occupancy_T_wg);
  }
  draw_grid(image, project, view.grid_step_m);

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
  if (layers.ground_truth) {
    draw_polyline(image, project, scene.ground_truth_w, colours::kGroundTruth, kGroundTruthThicknessPx);
  }
  if (layers.trajectory)
    draw_polyline(image, project, scene.trajectory_w, colours::kTrajectory, kTrajectoryThicknessPx);
  if (layers.keyframes) {
    for (const Pose3& T_wc : scene.keyframes_T_wc) {
      draw_frustum(image, project, T_wc, scene.camera, frustum_m, colours::kKeyframe, 1);
      ++view.frustums_drawn;
    }
  }
  if (scene.has_camera)
    draw_frustum(image, project, scene.current_T_wc, scene.camera, 2.0 * frustum_m, colours::kCurrentCamera, 2);

  draw_scale_bar(image, view.grid_step_m, project.scale());
  draw_axes(image);
  const std::string legend = std::string("top view, fit ") + (fit_ == TopViewFit::kMap ? "map" : "trajectory") + "  " +
                             std::to_string(scene.map_keyframes) + " keyframes  " + std::to_string(scene.map_points) +
                             " points  " + std::to_string(scene.loop_corrections) + " loop corrections  " +
                             std::to_string(static_cast<int>(project.scale())) + " px/m";
  cv::putText(image, legend, {8, 16}, cv::FONT_HERSHEY_SIMPLEX, 0.45, colours::kText, 1, cv::LINE_AA);
  return view;
}

}  // namespace heslam::viewer

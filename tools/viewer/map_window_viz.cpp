// MapWindow with OpenCV viz (see map_window.hpp).
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>

#include <opencv2/viz.hpp>

#include "tools/viewer/colours.hpp"
#include "tools/viewer/map_window.hpp"

namespace heslam::viewer {
namespace {

constexpr int kPointSizePx = 2;
// Frustum size in metres (EuRoC-sized scenes; the view zooms with the mouse).
constexpr double kFrustumScaleM = 0.08;
constexpr double kCurrentFrustumScaleM = 0.15;
// Follow mode: the viewer sits this far behind and above the current camera.
constexpr double kFollowBackM = 1.5;
constexpr double kFollowUpM = 0.7;
const cv::Size kWindowSize(1024, 768);

cv::viz::Color colour(const cv::Scalar& bgr) { return cv::viz::Color(bgr[0], bgr[1], bgr[2]); }
cv::Vec3d vec(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }
cv::Affine3d affine(const Pose3& T) {
  cv::Matx33d R;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = T.linear()(r, c);
  }
  return cv::Affine3d(R, vec(T.translation()));
}

void keyboard(const cv::viz::KeyboardEvent& event, void* cookie) {
  if (event.action == cv::viz::KeyboardEvent::KEY_DOWN && event.code != 0) {
    static_cast<std::vector<int>*>(cookie)->push_back(static_cast<unsigned char>(event.code));
  }
}

class VizMapWindow final : public MapWindow {
 public:
  VizMapWindow() : window_("heslam map") {
    window_.setWindowSize(kWindowSize);
    window_.setBackgroundColor(colour(colours::kBackground), colour(colours::kBackground));
    window_.registerKeyboardCallback(keyboard, &pending_keys_);
    window_.showWidget("origin", cv::viz::WCoordinateSystem(0.2));
  }

  void update(const Scene& scene, const Layers& layers, bool map_changed, int spin_ms,
              std::vector<int>& keys) override {
    if (map_changed || layers_changed(layers)) rebuild(scene, layers);
    remove_if_shown("camera");
    if (scene.has_camera) {
      show("camera", camera_widget(scene.camera, kCurrentFrustumScaleM, colours::kCurrentCamera),
           affine(scene.current_T_wc));
      if (layers.follow_camera) follow(scene.current_T_wc);
    }
    window_.spinOnce(spin_ms, true);
    keys.insert(keys.end(), pending_keys_.begin(), pending_keys_.end());
    pending_keys_.clear();
  }

  bool closed() const override { return window_.wasStopped(); }
  cv::Mat screenshot() override { return window_.getScreenshot(); }

 private:
  static cv::viz::WCameraPosition camera_widget(const PinholeStereo& camera, double scale, const cv::Scalar& bgr) {
    if (camera.fx_px > 0.0) {
      const cv::Matx33d K(camera.fx_px, 0, camera.cx_px, 0, camera.fy_px, camera.cy_px, 0, 0, 1);
      return cv::viz::WCameraPosition(K, scale, colour(bgr));
    }
    return cv::viz::WCameraPosition(cv::Vec2d(1.0, 0.8), scale, colour(bgr));
  }

  bool layers_changed(const Layers& layers) {
    const auto key = std::make_tuple(layers.points, layers.culled_points, layers.keyframes, layers.covisibility,
                                     layers.spanning_tree, layers.ground_truth, layers.trajectory);
    const bool changed = !last_layers_ || *last_layers_ != key;
    last_layers_ = key;
    return changed;
  }

  void remove_if_shown(const std::string& id) {
    if (shown_.erase(id) != 0) window_.removeWidget(id);
  }
  void show(const std::string& id, const cv::viz::Widget3D& widget, const cv::Affine3d& pose = cv::Affine3d()) {
    window_.showWidget(id, widget, pose);
    shown_.insert({id, 0});
  }

  void rebuild(const Scene& scene, const Layers& layers) {
    // Everything but the origin and the current camera is rebuilt from the scene.
    for (auto it = shown_.begin(); it != shown_.end();) {
      if (it->first != "camera") {
        window_.removeWidget(it->first);
        it = shown_.erase(it);
      } else {
        ++it;
      }
    }
    if (layers.points) show_points(scene, layers);
    if (layers.keyframes) {
      for (std::size_t i = 0; i < scene.keyframes_T_wc.size(); ++i) {
        show("kf" + std::to_string(i), camera_widget(scene.camera, kFrustumScaleM, colours::kKeyframe),
             affine(scene.keyframes_T_wc[i]));
      }
    }
    if (layers.covisibility) show_edges("covis", scene.covisibility, colours::kCovisibility);
    if (layers.spanning_tree) show_edges("tree", scene.spanning_tree, colours::kSpanningTree);
    if (layers.trajectory) show_path("trajectory", scene.trajectory_w, colours::kTrajectory);
    if (layers.ground_truth) show_path("ground_truth", scene.ground_truth_w, colours::kGroundTruth);
  }

  void show_points(const Scene& scene, const Layers& layers) {
    cv::Mat cloud(1, static_cast<int>(scene.points.size()), CV_64FC3);
    cv::Mat cloud_colours(1, cloud.cols, CV_8UC3);
    int n = 0;
    for (const ScenePoint& point : scene.points) {
      if (point.category == PointCategory::kCulled && !layers.culled_points) continue;
      cloud.at<cv::Vec3d>(0, n) = vec(point.p_w);
      const cv::Scalar c = colours::of(point.category);
      cloud_colours.at<cv::Vec3b>(0, n) =
          cv::Vec3b(static_cast<uchar>(c[0]), static_cast<uchar>(c[1]), static_cast<uchar>(c[2]));
      ++n;
    }
    if (n == 0) return;
    cv::viz::WCloud widget(cloud.colRange(0, n), cloud_colours.colRange(0, n));
    widget.setRenderingProperty(cv::viz::POINT_SIZE, kPointSizePx);
    show("points", widget);
  }

  // Edges grouped by their first end into one polyline per group (a -> b, a -> c drawn as b a c):
  // a few hundred widgets instead of thousands of lines.
  void show_edges(const std::string& prefix, const std::vector<SceneEdge>& edges, const cv::Scalar& bgr) {
    std::map<std::tuple<double, double, double>, std::vector<Eigen::Vector3d>> stars;
    for (const SceneEdge& edge : edges) {
      stars[{edge.from_w.x(), edge.from_w.y(), edge.from_w.z()}].push_back(edge.to_w);
    }
    int index = 0;
    for (const auto& [from, ends] : stars) {
      const Eigen::Vector3d centre(std::get<0>(from), std::get<1>(from), std::get<2>(from));
      std::vector<cv::Vec3d> path;
      for (const Eigen::Vector3d& end : ends) {
        path.push_back(vec(end));
        path.push_back(vec(centre));
      }
      show(prefix + std::to_string(index++), cv::viz::WPolyLine(path, colour(bgr)));
    }
  }

  void show_path(const std::string& id, const std::vector<Eigen::Vector3d>& points, const cv::Scalar& bgr) {
    if (points.size() < 2) return;
    std::vector<cv::Vec3d> path;
    for (const Eigen::Vector3d& p : points) path.push_back(vec(p));
    show(id, cv::viz::WPolyLine(path, colour(bgr)));
  }

  void follow(const Pose3& T_wc) {
    const Eigen::Vector3d eye = T_wc * Eigen::Vector3d(0.0, -kFollowUpM, -kFollowBackM);
    const Eigen::Vector3d up = T_wc.linear() * Eigen::Vector3d(0.0, -1.0, 0.0);  // camera y points down
    window_.setViewerPose(cv::viz::makeCameraPose(vec(eye), vec(T_wc.translation()), vec(up)));
  }

  cv::viz::Viz3d window_;
  std::vector<int> pending_keys_;
  std::map<std::string, int> shown_;
  std::optional<std::tuple<bool, bool, bool, bool, bool, bool, bool>> last_layers_;
};

}  // namespace

std::unique_ptr<MapWindow> MapWindow::create() { return std::make_unique<VizMapWindow>(); }

}  // namespace heslam::viewer

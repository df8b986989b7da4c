// The interactive 3D view (OpenCV viz, VTK): map points by category, keyframe frustums, the
// covisibility graph and spanning tree, the current camera, trajectory and ground truth; follow or
// free camera. Needs an X display. Built only when OpenCV's viz module is found (HESLAM_VIEWER_VIZ);
// otherwise `create()` returns null and the viewer shows the top view in a highgui window instead.
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "tools/viewer/layers.hpp"
#include "tools/viewer/scene.hpp"

namespace heslam::viewer {

class MapWindow {
 public:
  virtual ~MapWindow() = default;
  // Null when viz is not built in. Throws std::runtime_error when the window cannot be opened.
  static std::unique_ptr<MapWindow> create();

  // Redraws the map widgets from `scene` (the camera pose every call; the map only when
  // `map_changed`, since rebuilding VTK actors costs milliseconds), and processes window events
  // for `spin_ms`. Keys pressed in the window are appended to `keys`.
  virtual void update(const Scene& scene, const Layers& layers, bool map_changed, int spin_ms,
                      std::vector<int>& keys) = 0;
  // The user closed the window.
  virtual bool closed() const = 0;
  virtual cv::Mat screenshot() = 0;
};

}  // namespace heslam::viewer

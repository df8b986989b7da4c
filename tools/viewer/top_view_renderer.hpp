// The map seen from above, drawn with plain OpenCV (orthographic, no display needed): the headless
// 3D view and the map picture of every snapshot. "Above" is the first camera's -y axis (the world
// frame is the first camera's: x right, y down, z forward), so the image shows x to the right and z
// (forward) up; the view fits everything drawn.
#pragma once

#include <cstddef>

#include <opencv2/core.hpp>

#include "tools/viewer/layers.hpp"
#include "tools/viewer/scene.hpp"

namespace heslam::viewer {

struct TopView {
  cv::Mat image;                   // BGR
  std::size_t frustums_drawn = 0;  // keyframe frustums (== scene.keyframes_T_wc.size() with the layer on)
  std::size_t points_drawn = 0;
};

class TopViewRenderer {
 public:
  explicit TopViewRenderer(cv::Size size) : size_(size) {}
  TopView render(const Scene& scene, const Layers& layers) const;

 private:
  cv::Size size_;
};

}  // namespace heslam::viewer

// The map seen from above, drawn with plain OpenCV (orthographic, no display needed): the headless
// 3D view and the map picture of every snapshot. "Above" is the first camera's -y axis (the world
// frame is the first camera's: x right, y down, z forward), so the image shows x to the right and z
// (forward) up. By default the view fits the trajectory (the estimate, the ground truth and the
// current camera), so a 1 m path inside a 14 m map is not a 30-pixel blob; TopViewFit::kMap fits the
// map (points, keyframes and all). A grid at a round step (1, 2 or 5 x 10^k m), a scale bar of one
// grid step and an axis cross tell the size and the directions. heslam-occupancy's 2D grid, when one
// arrived, is drawn first (under everything): each known cell as its square, through the grid's T_wg.
#pragma once

#include <cstddef>

#include <opencv2/core.hpp>

#include "tools/viewer/layers.hpp"
#include "tools/viewer/scene.hpp"

namespace heslam::viewer {

// The picture's size when nothing else is asked for (heslam-viewer's snapshots).
inline const cv::Size kDefaultTopViewSize(900, 900);

// What the view is fitted to: the trajectory (the estimated positions, the ground truth when its
// layer is on, the current camera; the whole map while no trajectory arrived yet) or the map
// (its points, 2nd..98th percentile, keyframes, trajectories).
enum class TopViewFit { kTrajectory, kMap };

struct TopView {
  cv::Mat image;                   // BGR
  std::size_t frustums_drawn = 0;  // keyframe frustums (== scene.keyframes_T_wc.size() with the layer on)
  std::size_t points_drawn = 0;
  std::size_t occupancy_cells_drawn = 0;  // occupied + free cells of scene.occupancy inside the picture
  double scale_px_per_m = 0.0;            // the projection's scale
  double grid_step_m = 0.0;               // the grid's step, also the scale bar's length
};

class TopViewRenderer {
 public:
  explicit TopViewRenderer(cv::Size size, TopViewFit fit = TopViewFit::kTrajectory) : size_(size), fit_(fit) {}
  TopView render(const Scene& scene, const Layers& layers) const;

 private:
  cv::Size size_;
  TopViewFit fit_;
};

}  // namespace heslam::viewer

// Which layers of the 3D / top view are shown and how the 3D camera moves; toggled by keys
// (`toggle()` maps a key to a layer, documented in heslam-viewer --help).
#pragma once

namespace heslam::viewer {

struct Layers {
  bool points = true;
  bool culled_points = true;
  bool keyframes = true;
  bool covisibility = true;
  bool spanning_tree = true;
  bool ground_truth = true;
  bool trajectory = true;
  bool occupancy = true;      // heslam-occupancy's 2D grid under the top view
  bool follow_camera = true;  // false: free camera (mouse)

  // Applies a key; returns false when the key means nothing to the layers.
  bool toggle(int key) {
    switch (key) {
      case 'p': points = !points; return true;
      case 'u': culled_points = !culled_points; return true;
      case 'k': keyframes = !keyframes; return true;
      case 'c': covisibility = !covisibility; return true;
      case 't': spanning_tree = !spanning_tree; return true;
      case 'g': ground_truth = !ground_truth; return true;
      case 'j': trajectory = !trajectory; return true;
      case 'o': occupancy = !occupancy; return true;
      case 'f': follow_camera = !follow_camera; return true;
      default: return false;
    }
  }
};

}  // namespace heslam::viewer

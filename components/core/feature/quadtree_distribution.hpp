// ORB-SLAM2's quadtree keypoint distribution: split the area into quadrants until there are at
// least `wanted` non-empty cells (or no cell can be split), then keep the strongest point per cell.
// Spreads features over the image instead of piling them on the most textured spot.
#pragma once

#include <span>
#include <vector>

namespace heslam {

struct ScoredPoint {
  float x = 0.f;
  float y = 0.f;
  float response = 0.f;
};

// Indices into `points` of the kept points (one per final cell; may exceed `wanted` by at most 3, as
// ORB-SLAM2). Points must lie inside [min_x, max_x] x [min_y, max_y]. Deterministic: ties between
// cells are broken by creation order, ties in response by the lower index.
std::vector<int> distribute_quadtree(std::span<const ScoredPoint> points, float min_x, float max_x, float min_y,
                                     float max_y, int wanted);

}  // namespace heslam

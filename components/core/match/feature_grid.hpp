// Keypoints of one image binned in a uniform grid, for fast "which keypoints are near (u, v)" queries
// (projection search, stereo and frame-to-frame matching).
#pragma once

#include <span>
#include <vector>

#include "components/core/feature/features.hpp"

namespace heslam {

struct FeatureGridOptions {
  // Cell side in pixels. ORB-SLAM2 uses 64x48 cells over 640x480 images, i.e. about 10 px.
  float cell_size_px = 10.f;
};

class FeatureGrid {
 public:
  FeatureGrid() = default;
  // Keeps a copy of each keypoint's position and octave; indices refer to `keypoints`. Keypoints
  // outside [0, width) x [0, height) are clamped into the border cells (they still answer queries).
  FeatureGrid(std::span<const Keypoint> keypoints, int width_px, int height_px, const FeatureGridOptions& options = {});

  // Indices (ascending) of keypoints with |u - u_px| < radius_px and |v - v_px| < radius_px (a square
  // window, as ORB-SLAM2) and min_level <= octave <= max_level; -1 means no limit on that side.
  std::vector<int> in_area(float u_px, float v_px, float radius_px, int min_level = -1, int max_level = -1) const;
  // The same indices into `out` (cleared first): a search over many points reuses one buffer
  // instead of allocating a vector per query.
  void in_area(float u_px, float v_px, float radius_px, int min_level, int max_level, std::vector<int>& out) const;

  std::size_t size() const { return u_px_.size(); }
  int cols() const { return cols_; }
  int rows() const { return rows_; }

 private:
  int cell_col(float u_px) const;
  int cell_row(float v_px) const;

  float inv_cell_size_ = 0.1f;
  int cols_ = 0;
  int rows_ = 0;
  std::vector<float> u_px_;
  std::vector<float> v_px_;
  std::vector<int> octave_;
  // Compressed rows: the keypoints of cell c are cell_items_[cell_start_[c] .. cell_start_[c + 1]).
  std::vector<int> cell_start_;
  std::vector<int> cell_items_;
};

}  // namespace heslam

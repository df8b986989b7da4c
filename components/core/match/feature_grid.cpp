// Uniform grid over keypoints, stored as compressed rows (one counting pass, one filling pass).
#include "components/core/match/feature_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace heslam {

FeatureGrid::FeatureGrid(std::span<const Keypoint> keypoints, int width_px, int height_px,
                         const FeatureGridOptions& options) {
  if (width_px <= 0 || height_px <= 0 || !(options.cell_size_px > 0.f)) {
    throw std::runtime_error("FeatureGrid: expected a positive image size and cell_size_px");
  }
  inv_cell_size_ = 1.f / options.cell_size_px;
  cols_ = std::max(1, static_cast<int>(std::ceil(width_px * inv_cell_size_)));
  rows_ = std::max(1, static_cast<int>(std::ceil(height_px * inv_cell_size_)));

  const std::size_t n = keypoints.size();
  u_px_.resize(n);
  v_px_.resize(n);
  octave_.resize(n);
  std::vector<int> cell_of(n);
  cell_start_.assign(static_cast<std::size_t>(cols_ * rows_) + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    u_px_[i] = keypoints[i].u_px;
    v_px_[i] = keypoints[i].v_px;
    octave_[i] = keypoints[i].octave;
    cell_of[i] = cell_row(v_px_[i]) * cols_ + cell_col(u_px_[i]);
    ++cell_start_[static_cast<std::size_t>(cell_of[i]) + 1];
  }
  for (std::size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  cell_items_.resize(n);
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) cell_items_[static_cast<std::size_t>(fill[cell_of[i]]++)] = static_cast<int>(i);
}

int FeatureGrid::cell_col(float u_px) const {
  return std::clamp(static_cast<int>(std::floor(u_px * inv_cell_size_)), 0, cols_ - 1);
}

int FeatureGrid::cell_row(float v_px) const {
  return std::clamp(static_cast<int>(std::floor(v_px * inv_cell_size_)), 0, rows_ - 1);
}

std::vector<int> FeatureGrid::in_area(float u_px, float v_px, float radius_px, int min_level, int max_level) const {
  std::vector<int> result;
  in_area(u_px, v_px, radius_px, min_level, max_level, result);
  return result;
}

void FeatureGrid::in_area(float u_px, float v_px, float radius_px, int min_level, int max_level,
                          std::vector<int>& result) const {
  result.clear();
  if (u_px_.empty() || !(radius_px > 0.f)) return;
  const int col0 = cell_col(u_px - radius_px);
  const int col1 = cell_col(u_px + radius_px);
  const int row0 = cell_row(v_px - radius_px);
  const int row1 = cell_row(v_px + radius_px);
  // No level limit: the whole int range. The cells col0..col1 of one row are contiguous in
  // cell_items_ (compressed rows), so each row of the window is one run of items.
  const int lowest = min_level >= 0 ? min_level : std::numeric_limits<int>::min();
  const int highest = max_level >= 0 ? max_level : std::numeric_limits<int>::max();
  for (int row = row0; row <= row1; ++row) {
    const int end = cell_start_[row * cols_ + col1 + 1];
    for (int k = cell_start_[row * cols_ + col0]; k < end; ++k) {
      const int i = cell_items_[k];
      const int octave = octave_[i];
      if (octave < lowest || octave > highest) continue;
      if (std::abs(u_px_[i] - u_px) < radius_px && std::abs(v_px_[i] - v_px) < radius_px) result.push_back(i);
    }
  }
  std::sort(result.begin(), result.end());
}

}  // namespace heslam

// The 2D occupancy grid a navigation stack plans on: a height band of a VoxelMap seen from above, and
// its files in the format nav2's map_server loads (STEM.pgm + STEM.yaml: image, resolution, origin,
// negate, occupied_thresh, free_thresh).
//
// Frames: the voxel map's z axis is "up"; cell (i, j) covers x in [i, i+1) and y in [j, j+1) times
// the resolution, the same lattice as the voxels. Cells are kept by their lattice index, so two grids
// of one frame compare cell by cell whatever their extents.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>

#include "components/core/occupancy/voxel_map.hpp"

namespace heslam {

enum class CellState : std::uint8_t { kUnknown, kFree, kOccupied };

struct GridBand {
  // Voxels whose centre lies in [min_m, max_m] along z vote for their column.
  double min_m = -0.7;
  double max_m = 0.3;
};

class OccupancyGrid {
 public:
  explicit OccupancyGrid(double resolution_m = 0.05) : resolution_m_(resolution_m) {}

  // A column is occupied when one of its voxels in the band is occupied, else free when one is free,
  // else unknown (absent).
  static OccupancyGrid from_voxels(const VoxelMap& voxels, const GridBand& band);

  double resolution_m() const { return resolution_m_; }
  CellState at(int i, int j) const;
  void set(int i, int j, CellState state);
  const std::map<std::pair<int, int>, CellState>& cells() const { return cells_; }
  std::size_t count(CellState state) const;

  // Writes STEM.pgm and STEM.yaml (map_server: occupied 0, free 254, unknown 205; origin = the
  // lower-left pixel's corner; row 0 of the image is the largest y). An empty grid is written as one
  // unknown cell at the origin. Each file is replaced atomically. Throws std::runtime_error naming the file.
  void write_map_server(const std::filesystem::path& stem) const;
  // Reads a grid written by write_map_server (or any map_server trinary map whose origin lies on the
  // resolution's lattice). Throws std::runtime_error naming the file and field.
  static OccupancyGrid read_map_server(const std::filesystem::path& yaml_file);

 private:
  double resolution_m_;
  std::map<std::pair<int, int>, CellState> cells_;  // (i, j) -> state; unknown cells are absent
};

// How a grid agrees with a ground truth of the same lattice.
struct GridAgreement {
  std::size_t truth_occupied = 0;
  std::size_t grid_occupied = 0;
  std::size_t both_occupied = 0;
  double occupied_iou = 0.0;               // |A and B| / |A or B| of occupied cells
  std::size_t free_in_truth_occupied = 0;  // cells the grid calls free that the truth says are occupied
  std::size_t truth_occupied_unknown = 0;  // truth-occupied cells the grid never observed
  // Where the disagreement lies (Chebyshev distance in cells, 1, 2, 3 or more): grid-occupied cells
  // outside the truth by their distance to the nearest truth-occupied cell, truth-occupied cells the
  // grid misses by their distance to the nearest grid-occupied cell. Mostly at 1: the surfaces are found
  // and misplaced (or thickened) by less than a cell; farther: false surfaces or missed ones.
  std::size_t extra_at[3] = {0, 0, 0};
  std::size_t missed_at[3] = {0, 0, 0};
};
// Throws std::invalid_argument when the resolutions differ.
GridAgreement compare(const OccupancyGrid& grid, const OccupancyGrid& truth);

}  // namespace heslam

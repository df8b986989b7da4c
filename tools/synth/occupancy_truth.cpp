// Ground-truth occupancy of a synthetic scene (see occupancy_truth.hpp).
#include "tools/synth/occupancy_truth.hpp"

#include <cmath>

namespace heslam::synth {
namespace {

// Samples per cell side along each quad axis: fine enough that a surface crossing a cell's corner
// still leaves a sample in it (a sample every 1/8 cell misses at most a sliver of 1/8 cell).
constexpr double kSamplesPerCell = 8.0;

}  // namespace

OccupancyGrid occupancy_truth(const Scene& scene, const Pose3& T_wc0, double resolution_m, const GridBand& band) {
  OccupancyGrid grid(resolution_m);
  const Pose3 T_c0w = T_wc0.inverse();
  const double step = resolution_m / kSamplesPerCell;
  for (const Quad& quad : scene.quads) {
    const int nu = static_cast<int>(std::ceil(quad.size_u_m / step));
    const int nv = static_cast<int>(std::ceil(quad.size_v_m / step));
    for (int a = 0; a <= nu; ++a) {
      for (int b = 0; b <= nv; ++b) {
        const Eigen::Vector3d p_c =
            T_c0w * quad.point(std::min(a * step, quad.size_u_m), std::min(b * step, quad.size_v_m));
        // Grid frame of up = -y: (x, z, -y).
        const double height = -p_c.y();
        if (height < band.min_m || height > band.max_m) continue;
        grid.set(static_cast<int>(std::floor(p_c.x() / resolution_m)),
                 static_cast<int>(std::floor(p_c.z() / resolution_m)), CellState::kOccupied);
      }
    }
  }
  return grid;
}

}  // namespace heslam::synth

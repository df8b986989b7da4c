// Ground-truth occupancy of a synthetic scene (see occupancy_truth.hpp).
#include "tools/synth/occupancy_truth.hpp"

#include <cmath>

#include <opencv2/core.hpp>

namespace heslam::synth {
namespace {

// Samples per cell side along each quad axis: fine enough that a surface crossing a cell's corner
// still leaves a sample in it (a sample every 1/8 cell misses at most a sliver of 1/8 cell).
constexpr double kSamplesPerCell = 8.0;

// A point of the first camera's frame into the grid (up = -y: grid (x, z), height -y), when the centre
// of its voxel lies in the band.
void mark(OccupancyGrid& grid, const Eigen::Vector3d& p_c, double resolution_m, const GridBand& band) {
  const double voxel_centre = (std::floor(-p_c.y() / resolution_m) + 0.5) * resolution_m;
  if (voxel_centre < band.min_m || voxel_centre > band.max_m) return;
  grid.set(static_cast<int>(std::floor(p_c.x() / resolution_m)), static_cast<int>(std::floor(p_c.z() / resolution_m)),
           CellState::kOccupied);
}

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
        mark(grid, T_c0w * quad.point(std::min(a * step, quad.size_u_m), std::min(b * step, quad.size_v_m)),
             resolution_m, band);
      }
    }
  }
  return grid;
}

OccupancyGrid occupancy_truth_seen(SequenceRenderer& renderer, int stride, double max_depth_m, double resolution_m,
                                   const GridBand& band) {
  OccupancyGrid grid(resolution_m);
  const Pose3 T_c0w = renderer.T_wc_left(0).inverse();
  const CameraRays& rays = renderer.rays();  // the pixels' rays, distorted or not
  cv::Mat radiance, depth;
  for (int index = 0; index < renderer.num_frames(); index += std::max(1, stride)) {
    renderer.render_radiance_left(index, radiance, &depth);
    const Pose3 T_c0c = T_c0w * renderer.T_wc_left(index);
    for (int v = 0; v < depth.rows; ++v) {
      const float* row = depth.ptr<float>(v);
      for (int u = 0; u < depth.cols; ++u) {
        const double z = row[u];
        if (!(z > 0.0) || z > max_depth_m) continue;
        const int pixel = v * rays.width_px() + u;
        const Eigen::Vector3d p(rays.x(pixel) * z, rays.y(pixel) * z, z);
        mark(grid, T_c0c * p, resolution_m, band);
      }
    }
  }
  return grid;
}

}  // namespace heslam::synth

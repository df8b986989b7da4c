// The ground-truth 2D occupancy of a synthetic scene, in the frame heslam-occupancy's grid uses: the
// first left camera's frame (the SLAM world without an IMU) with -y up, so that the grid of a run and
// this truth share one lattice cell by cell (components/core/occupancy/occupancy_map.hpp).
//
// The band is the grid's own: a surface point counts when the centre of its voxel (the cube of side
// resolution_m on the lattice of the frame, as the voxel map quantizes heights) lies in [min, max], so
// a surface near the band's edge is in or out of both alike.
#pragma once

#include "components/core/geometry/pose.hpp"
#include "components/core/occupancy/occupancy_grid.hpp"
#include "tools/synth/scene.hpp"
#include "tools/synth/sequence.hpp"

namespace heslam::synth {

// A cell is occupied when a surface of the scene passes through its column within the band (heights
// along -y of the camera T_wc0, from its centre). Surfaces are sampled every resolution / 8.
OccupancyGrid occupancy_truth(const Scene& scene, const Pose3& T_wc0, double resolution_m, const GridBand& band);

// The part of occupancy_truth a camera on the sequence's path can see: the surface points the left
// camera sees (the renderer's depth, every pixel) within max_depth_m in every `stride`-th frame. A
// mapper that sees only through that camera can at best find these cells (a table no frame looks at
// is occupied in occupancy_truth, unknown to any mapper).
OccupancyGrid occupancy_truth_seen(SequenceRenderer& renderer, int stride, double max_depth_m, double resolution_m,
                                   const GridBand& band);

}  // namespace heslam::synth

// The ground-truth 2D occupancy of a synthetic scene, in the frame heslam-occupancy's grid uses: the
// first left camera's frame (the SLAM world without an IMU) with -y up, so that the grid of a run and
// this truth share one lattice cell by cell (components/core/occupancy/occupancy_map.hpp).
#pragma once

#include "components/core/geometry/pose.hpp"
#include "components/core/occupancy/occupancy_grid.hpp"
#include "tools/synth/scene.hpp"

namespace heslam::synth {

// A cell is occupied when a surface of the scene passes through its column within the band (heights
// along -y of the camera T_wc0, from its centre). Surfaces are sampled every resolution / 8.
OccupancyGrid occupancy_truth(const Scene& scene, const Pose3& T_wc0, double resolution_m, const GridBand& band);

}  // namespace heslam::synth

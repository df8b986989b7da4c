// heslam-occupancy: dense stereo depth per keyframe fused into a 3D occupancy map and a 2D grid for
// navigation (see occupancy_node.hpp and docs/occupancy.md).
#include "components/occupancy/occupancy_node.hpp"

int main(int argc, char** argv) {
  return heslam::runtime::component_main<heslam::occupancy::OccupancyNode>(argc, argv, "occupancy");
}

// heslam-local-mapper: the map owner process (local mapping of ORB-SLAM2 over DDS).
//   heslam-local-mapper [common options] [--map-file FILE] [--load-map FILE] [--save-map FILE]
#include "components/local_mapper/mapper_node.hpp"

int main(int argc, char** argv) {
  return heslam::runtime::component_main<heslam::local_mapper::MapperNode>(argc, argv, "local_mapper");
}

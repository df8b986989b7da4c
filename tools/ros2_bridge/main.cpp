// heslam-ros2-bridge: heslam's odometry, keyframe trajectory and map points as ROS 2 topics.
//   heslam-ros2-bridge [common options] [--config bridge.yaml]
#include "tools/ros2_bridge/ros2_bridge.hpp"

int main(int argc, char** argv) {
  return heslam::runtime::component_main<heslam::ros2::Ros2Bridge>(argc, argv, "ros2_bridge");
}

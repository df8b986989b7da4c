// heslam-ros2-input: a ROS 2 stereo camera's topics as heslam's camera/stereo and camera/calibration.
//   heslam-ros2-input [common options] [--config input.yaml]
#include "tools/ros2_bridge/ros2_input.hpp"

int main(int argc, char** argv) {
  return heslam::runtime::component_main<heslam::ros2::Ros2Input>(argc, argv, "ros2_input");
}

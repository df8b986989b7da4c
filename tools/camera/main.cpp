// heslam-camera: publishes a live stereo camera (or a video file / image folder played as one) on the
// camera topics, as heslam-replay publishes a recording.
#include <iostream>

#include "runtime/args.hpp"
#include "runtime/shutdown.hpp"
#include "tools/camera/camera.hpp"
#include "tools/camera/camera_options.hpp"

int main(int argc, char** argv) {
  try {
    heslam::runtime::install_shutdown_handlers();
    const heslam::runtime::CommonArgs common = heslam::runtime::parse_common_args(argc, argv, "camera");
    if (common.help) {
      std::cout << heslam::camera_usage() << heslam::runtime::common_args_usage();
      return 0;
    }
    const heslam::CameraOptions options = heslam::parse_camera_options(common.rest);
    if (common.check) return heslam::check_camera(options);
    return heslam::run_camera(common, options);
  } catch (const std::exception& error) {
    std::cerr << "heslam-camera: " << error.what() << "\n";
    return 1;
  }
}

// heslam-replay: publishes an EuRoC or KITTI recording on the camera topics (like `ros2 bag play`).
#include <iostream>

#include "runtime/args.hpp"
#include "runtime/shutdown.hpp"
#include "tools/replay/replay_options.hpp"
#include "tools/replay/replayer.hpp"

int main(int argc, char** argv) {
  try {
    heslam::runtime::install_shutdown_handlers();
    const heslam::runtime::CommonArgs common = heslam::runtime::parse_common_args(argc, argv, "replay");
    if (common.help) {
      std::cout << heslam::replay_usage() << heslam::runtime::common_args_usage();
      return 0;
    }
    const heslam::ReplayOptions options = heslam::parse_replay_options(common.rest);
    // --check: the options and the dataset (its calibration included), as a run would open them.
    if (common.check) return heslam::check_replay(options);
    return heslam::run_replay(common, options);
  } catch (const std::exception& error) {
    std::cerr << "heslam-replay: " << error.what() << "\n";
    return 1;
  }
}

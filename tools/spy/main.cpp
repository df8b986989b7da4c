// heslam-spy: taps live topics (like `ros2 topic list|echo|hz|bw|info`).
#include <iostream>

#include "runtime/args.hpp"
#include "runtime/shutdown.hpp"
#include "tools/spy/spy_commands.hpp"
#include "tools/spy/spy_options.hpp"

int main(int argc, char** argv) {
  try {
    heslam::runtime::install_shutdown_handlers();
    const heslam::runtime::CommonArgs common = heslam::runtime::parse_common_args(argc, argv, "spy");
    if (common.help) {
      std::cout << heslam::spy_usage() << heslam::runtime::common_args_usage();
      return 0;
    }
    const heslam::SpyOptions options = heslam::parse_spy_options(common.rest);
    if (common.check) return 0;
    return heslam::run_spy(common, options);
  } catch (const std::exception& error) {
    std::cerr << "heslam-spy: " << error.what() << "\n";
    return 1;
  }
}

// heslam-viewer: shows the map being built and the current frame of a running pipeline (see
// viewer_node.hpp and docs/tools/viewer.md).
#include <iostream>

#include "runtime/args.hpp"
#include "runtime/shutdown.hpp"
#include "tools/viewer/viewer_node.hpp"
#include "tools/viewer/viewer_options.hpp"

int main(int argc, char** argv) {
  using namespace heslam;
  try {
    runtime::install_shutdown_handlers();
    const runtime::CommonArgs args = runtime::parse_common_args(argc, argv, "viewer");
    if (args.help) {
      std::cout << viewer::ViewerOptions::usage() << runtime::common_args_usage();
      return 0;
    }
    if (args.check) return 0;  // its options are read as it starts; the common flags are checked
    viewer::ViewerNode node(args);
    return node.execute();
  } catch (const std::exception& error) {
    std::cerr << "heslam-viewer: " << error.what() << "\n";
    return 1;
  }
}

// heslam-frontend: stereo frames in, poses and keyframes out (see frontend.hpp and docs/frontend.md).
#include "components/frontend/frontend.hpp"

int main(int argc, char** argv) {
  return heslam::runtime::component_main<heslam::frontend::Frontend>(argc, argv, "frontend");
}

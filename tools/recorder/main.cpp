// heslam-recorder: writes the run's trajectory at shutdown (see recorder.hpp and docs/recorder.md).
#include "tools/recorder/recorder.hpp"

int main(int argc, char** argv) {
  return heslam::runtime::component_main<heslam::recorder::Recorder>(argc, argv, "recorder");
}

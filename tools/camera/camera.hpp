// heslam-camera's engine: publishes the calibration (transient-local) and the stereo frames of a live
// source as they come, with the replay's topics and messages (tools/replay/replay_messages.hpp).
#pragma once

#include "runtime/args.hpp"
#include "tools/camera/camera_options.hpp"

namespace heslam {

// Opens the calibration, the source and the DDS entities; publishes until the source ends or
// SIGINT/SIGTERM. Returns 0 for a recording played to its end or a stop by signal; 1 when the source
// ended abnormally (a device that stopped delivering frames, --end fail, bad input mid-run) or no
// frame was published, its last line saying so. Throws std::runtime_error with one line on an error
// at start (calibration, a source that cannot be opened).
int run_camera(const runtime::CommonArgs& common, const CameraOptions& options);

// --check: the calibration rectified, the source opened and its first pair read and checked against
// the calibration, without DDS; 0, or throws with the line a run would fail with.
int check_camera(const CameraOptions& options);

}  // namespace heslam

// heslam-replay's engine: publishes a dataset's calibration (transient-local) and its stereo frames,
// paced by the recording's stamps (--rate) or by the consumer's FrameDone (--lockstep).
#pragma once

#include "runtime/args.hpp"
#include "tools/replay/replay_options.hpp"

namespace heslam {

// Opens the dataset and DDS entities, publishes, prints the summary. Returns the exit code (0 also
// when interrupted by SIGINT/SIGTERM or 'q'); throws std::runtime_error with one line on any error
// (dataset, calibration, --strict image error, lockstep consumer missing or silent).
int run_replay(const runtime::CommonArgs& common, const ReplayOptions& options);

// --check: opens the dataset and rectifies its calibration as run_replay would, without DDS; 0, or
// throws with the line a run would fail with.
int check_replay(const ReplayOptions& options);

}  // namespace heslam

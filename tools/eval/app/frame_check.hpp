// heslam-eval's check that the estimate and the ground truth are poses of the same frame, from the
// estimate's `# heslam frame:` header (tools/eval/pose_frame.hpp): a body-frame estimate against a
// ground truth turned into camera poses (--extrinsic), or a camera estimate against EuRoC body poses,
// would give rotation errors of the extrinsic's size (~90 deg on EuRoC) and wrong translations.
#pragma once

#include <optional>
#include <string>

#include "tools/eval/app/cli_options.hpp"
#include "tools/eval/trajectory.hpp"

namespace heslam::eval::app {

struct FrameCheck {
  std::optional<std::string> error;    // the two files are of different frames: no figures
  std::optional<std::string> warning;  // comparable positions, rotations off by a known rotation
};

// The ground truth's frame: its own header, else body for EuRoC csv (cam0 with --extrinsic), else
// unknown. Nothing is checked when either frame is unknown.
FrameCheck check_frames(const CliOptions& options, const Trajectory& gt, const Trajectory& est);

}  // namespace heslam::eval::app

// An EuRoC ASL folder as a list of stereo frames (cam0/cam1 data.csv paired by stamp, read by the
// dataset library, tools/dataset/) and, when present, each frame's ground-truth body pose.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "components/core/geometry/pose.hpp"

namespace heslam::bench {

struct EurocFrame {
  std::int64_t stamp_ns = 0;
  std::filesystem::path left_png;
  std::filesystem::path right_png;
  std::optional<Pose3> T_WB_truth;  // the ground truth's body pose at this stamp (none: no row)
};

struct EurocSequence {
  std::filesystem::path mav0_dir;
  std::vector<EurocFrame> frames;  // in stamp order, both images listed
};

// dataset_dir is the folder holding mav0/ (or mav0 itself). Throws std::runtime_error with one line
// naming the file (and line) on a missing or malformed data.csv or ground truth. Rows of one camera
// without a partner in the other are skipped, as heslam-replay skips them.
EurocSequence load_euroc_sequence(const std::filesystem::path& dataset_dir);

}  // namespace heslam::bench

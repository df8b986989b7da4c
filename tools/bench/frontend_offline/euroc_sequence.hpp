// An EuRoC ASL folder as a list of stereo frames (cam0/cam1 data.csv paired by stamp) and, when
// present, the body ground truth at those stamps.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "components/core/geometry/pose.hpp"

namespace heslam::bench {

struct EurocFrame {
  std::int64_t stamp_ns = 0;
  std::filesystem::path left_png;
  std::filesystem::path right_png;
};

struct EurocSequence {
  std::filesystem::path mav0_dir;
  std::vector<EurocFrame> frames;             // in stamp order, both images present
  std::map<std::int64_t, Pose3> T_WB_by_stamp;  // ground truth body poses (empty when absent)
};

// dataset_dir is the folder holding mav0/ (or mav0 itself). Throws std::runtime_error with one line
// naming the file on a missing or malformed data.csv. Left frames without a right image are skipped.
EurocSequence load_euroc_sequence(const std::filesystem::path& dataset_dir);

}  // namespace heslam::bench

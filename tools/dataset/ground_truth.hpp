// A recording's ground truth next to its frames. The one reader of ground-truth files is heslam_eval's
// (tools/eval/trajectory_io.hpp: EuRoC csv with 8 or 17 columns, TUM, KITTI); this says where a
// EuRoC folder keeps it and pairs its poses with frames by stamp, for the tools that need the true
// pose of a frame (offline benchmarks, vocabulary scores, stereo comparisons).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "components/core/geometry/pose.hpp"
#include "tools/eval/trajectory.hpp"

namespace heslam {

// MAV0/state_groundtruth_estimate0/data.csv: body (IMU) poses, T_WB.
std::filesystem::path euroc_ground_truth_file(const std::filesystem::path& mav0_dir);

// For each stamp, the pose of `truth` whose stamp is nearest (the earlier one on a tie), when it is
// at most max_gap_s away; nullopt otherwise. `truth` must have stamps in increasing order, as the
// readers return them for EuRoC and TUM files.
std::vector<std::optional<Pose3>> poses_at_stamps(const eval::Trajectory& truth,
                                                  const std::vector<std::int64_t>& stamps_ns, double max_gap_s);

}  // namespace heslam

// The ground truth (--gt) drawn over the map: read once, then aligned to the estimate in the map's
// frame by SE(3) Umeyama on time-associated positions (as heslam-eval ape --align se3, the other way
// round: ground truth onto the estimate, so the map stays where the pipeline put it).
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "tools/eval/trajectory.hpp"

namespace heslam::viewer {

class GroundTruthOverlay {
 public:
  // Throws std::runtime_error naming the file when it cannot be read (heslam-eval's readers).
  GroundTruthOverlay(const std::filesystem::path& file, const std::filesystem::path& extrinsic);
  // The ground-truth positions in the estimate's frame; empty while fewer than 3 estimate stamps pair
  // with the ground truth (nothing to align on yet) or the estimate is still a single point.
  std::vector<Eigen::Vector3d> aligned(const std::vector<Eigen::Vector3d>& estimate_w,
                                       const std::vector<std::int64_t>& estimate_stamps_ns) const;

 private:
  eval::Trajectory ground_truth_;
};

}  // namespace heslam::viewer

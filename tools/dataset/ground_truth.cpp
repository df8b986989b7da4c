// Where EuRoC keeps its ground truth, and poses paired with frames by stamp (see ground_truth.hpp).
#include "tools/dataset/ground_truth.hpp"

#include <algorithm>
#include <cmath>

namespace heslam {
namespace {

// The readers turn a nanosecond stamp into seconds this way (tools/eval/euroc_format.cpp), so a frame
// stamped like its ground-truth row gets the same double, and a gap of exactly zero.
constexpr double kSecondsPerNanosecond = 1e-9;

}  // namespace

std::filesystem::path euroc_ground_truth_file(const std::filesystem::path& mav0_dir) {
  return mav0_dir / "state_groundtruth_estimate0" / "data.csv";
}

std::vector<std::optional<Pose3>> poses_at_stamps(const eval::Trajectory& truth,
                                                  const std::vector<std::int64_t>& stamps_ns, double max_gap_s) {
  std::vector<std::optional<Pose3>> poses(stamps_ns.size());
  const std::vector<double>& truth_s = truth.stamps_s;
  for (std::size_t i = 0; i < stamps_ns.size(); ++i) {
    const double stamp_s = static_cast<double>(stamps_ns[i]) * kSecondsPerNanosecond;
    const auto after = std::lower_bound(truth_s.begin(), truth_s.end(), stamp_s);
    auto nearest = after;
    if (after != truth_s.begin() && (after == truth_s.end() || stamp_s - *(after - 1) <= *after - stamp_s)) {
      nearest = after - 1;
    }
    if (nearest == truth_s.end() || std::abs(*nearest - stamp_s) > max_gap_s) continue;
    poses[i] = truth.poses_wc[static_cast<std::size_t>(nearest - truth_s.begin())];
  }
  return poses;
}

}  // namespace heslam

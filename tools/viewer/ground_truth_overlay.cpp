// Ground truth aligned onto the estimate (see ground_truth_overlay.hpp).
#include "tools/viewer/ground_truth_overlay.hpp"

#include <exception>

#include "tools/eval/alignment.hpp"
#include "tools/eval/association.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::viewer {
namespace {

constexpr std::size_t kMinPairs = 3;  // Umeyama needs three non-collinear pairs

}  // namespace

GroundTruthOverlay::GroundTruthOverlay(const std::filesystem::path& file, const std::filesystem::path& extrinsic) {
  eval::ReadOptions options;
  options.extrinsic_path = extrinsic;
  ground_truth_ = eval::read_trajectory(file, options);
}

std::vector<Eigen::Vector3d> GroundTruthOverlay::aligned(const std::vector<Eigen::Vector3d>& estimate_w,
                                                         const std::vector<std::int64_t>& estimate_stamps_ns) const {
  if (estimate_w.size() < kMinPairs || !ground_truth_.has_stamps()) return {};
  eval::Trajectory estimate;
  for (std::size_t i = 0; i < estimate_w.size(); ++i) {
    Pose3 T_wc = Pose3::Identity();
    T_wc.translation() = estimate_w[i];
    estimate.push_back(T_wc, static_cast<std::int64_t>(i), static_cast<double>(estimate_stamps_ns[i]) * 1e-9);
  }
  try {
    const eval::AlignedPair pair = eval::associate(ground_truth_, estimate);
    if (pair.size() < kMinPairs) return {};
    // Maps the ground truth onto the estimate: est ~ R gt + t.
    const eval::Sim3 S = eval::compute_alignment(pair.est, pair.gt, eval::AlignMode::se3);
    std::vector<Eigen::Vector3d> out;
    out.reserve(ground_truth_.size());
    const double first_s = estimate.stamps_s.front(), last_s = estimate.stamps_s.back();
    for (std::size_t i = 0; i < ground_truth_.size(); ++i) {
      // Only the part of the ground truth the run has covered so far.
      if (ground_truth_.stamps_s[i] < first_s || ground_truth_.stamps_s[i] > last_s) continue;
      out.push_back(S.scale * (S.R * ground_truth_.position_m(i)) + S.t);
    }
    return out;
  } catch (const std::exception&) {
    return {};  // nothing overlaps yet, or a degenerate (still) estimate: nothing to draw
  }
}

}  // namespace heslam::viewer

// EuRoC ASL frame lists and ground truth for the offline runs (see euroc_sequence.hpp).
#include "tools/bench/frontend_offline/euroc_sequence.hpp"

#include "tools/dataset/ground_truth.hpp"
#include "tools/dataset/stereo_dataset.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::bench {
namespace {

// A ground-truth row belongs to a frame stamped within this (EuRoC and heslam-synth write one row per
// frame, at the frame's own stamp).
constexpr double kMaxStampGapS = 1e-3;

}  // namespace

EurocSequence load_euroc_sequence(const std::filesystem::path& dataset_dir) {
  EurocSequence sequence;
  sequence.mav0_dir = std::filesystem::exists(dataset_dir / "mav0") ? dataset_dir / "mav0" : dataset_dir;
  // The runs rectify with their own calibration loader; only the frame lists are read here.
  const StereoDataset dataset =
      open_dataset(sequence.mav0_dir, {.format = DatasetFormat::kEuroc, .load_calibration = false});
  std::vector<std::int64_t> stamps_ns;
  for (const StereoFrameFiles& frame : dataset.frames) {
    sequence.frames.push_back({frame.stamp_ns, frame.left, frame.right, std::nullopt});
    stamps_ns.push_back(frame.stamp_ns);
  }
  const std::filesystem::path truth_file = euroc_ground_truth_file(sequence.mav0_dir);
  if (!std::filesystem::exists(truth_file)) return sequence;
  const eval::Trajectory truth = eval::read_trajectory(truth_file, {.format = eval::Format::euroc});
  const std::vector<std::optional<Pose3>> T_WB = poses_at_stamps(truth, stamps_ns, kMaxStampGapS);
  for (std::size_t i = 0; i < sequence.frames.size(); ++i) sequence.frames[i].T_WB_truth = T_WB[i];
  return sequence;
}

}  // namespace heslam::bench

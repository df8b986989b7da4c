// The two-agent proof's data and known answers (docs/agents.md), shared by the two-agent end-to-end tests:
// the shared MH01 clip split in two overlapping halves (test::make_euroc_part, euroc_parts.hpp), the loop
// closer's merge lines, and each agent's ATE when both trajectories are aligned to the ground truth ONCE (one
// SE(3) for the poses of both: one frame).
#pragma once

#include <cmath>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "euroc_parts.hpp"
#include "pipeline_runs.hpp"

namespace heslam::test {

inline constexpr int kHalfAFirstFrame = 0;   // agent a: frames 0-99 of the clip
inline constexpr int kHalfBFirstFrame = 60;  // agent b: frames 60-159
inline constexpr int kFramesPerHalf = 100;

// The loop closer's merge lines: the stamp (s) of the keyframe at which each merge happened.
inline std::vector<double> merge_stamps_s(const std::string& output) {
  static const std::regex line(R"(maps merged: map \d+ into map \d+ at keyframe \S+ \(stamp ([0-9.]+) s\))");
  std::vector<double> stamps;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line); it != std::sregex_iterator(); ++it) {
    stamps.push_back(std::stod((*it)[1]));
  }
  return stamps;
}

// Each agent's ATE (m) when both trajectories are aligned to their ground truth with one SE(3).
struct TwoAgentAte {
  double a_m = 0.0;
  double b_m = 0.0;
  double alone_a_m = 0.0;  // each aligned on its own, for the figures
  double alone_b_m = 0.0;
};

inline TwoAgentAte two_agent_ate(const std::filesystem::path& half_a, const eval::Trajectory& a,
                                 const std::filesystem::path& half_b, const eval::Trajectory& b) {
  const eval::AlignedPair pair_a = eval::associate(ground_truth_for(half_a, a), a);
  const eval::AlignedPair pair_b = eval::associate(ground_truth_for(half_b, b), b);
  eval::AlignedPair both = pair_a;
  for (std::size_t i = 0; i < pair_b.size(); ++i) {
    both.gt.push_back(pair_b.gt.poses_wc[i], pair_b.gt.frame_ids[i], pair_b.gt.stamps_s[i]);
    both.est.push_back(pair_b.est.poses_wc[i], pair_b.est.frame_ids[i], pair_b.est.stamps_s[i]);
  }
  const eval::ApeResult ape = eval::compute_ape(both);
  double sum_a = 0.0, sum_b = 0.0;
  for (std::size_t i = 0; i < ape.translation_errors_m.size(); ++i) {
    const double e2 = ape.translation_errors_m[i] * ape.translation_errors_m[i];
    (i < pair_a.size() ? sum_a : sum_b) += e2;
  }
  TwoAgentAte ate;
  ate.a_m = std::sqrt(sum_a / static_cast<double>(pair_a.size()));
  ate.b_m = std::sqrt(sum_b / static_cast<double>(pair_b.size()));
  ate.alone_a_m = eval::compute_ape(pair_a).translation_m.rmse;
  ate.alone_b_m = eval::compute_ape(pair_b).translation_m.rmse;
  return ate;
}

}  // namespace heslam::test

// Relative pose error, as evo's RPE: the error of the motion between two poses of a pair.
//
// API:
//   RpeResult rpe = compute_rpe(pair, RpeOptions{.delta = 10, .unit = DeltaUnit::meters});
//   rpe.translation_m.rmse, rpe.pairs.size()
// Pairs (i, j) (rows of the associated trajectories):
//   frames:  i = 0, d, 2d, ...; j = the next one (--all-pairs: every i, j = i + d)
//   meters:  walk the ESTIMATE accumulating the distance between consecutive positions; emit a row
//            each time the sum reaches delta and reset the sum; pairs are consecutive emitted rows.
//            --all-pairs: for every i the later row whose path distance is nearest to delta,
//            kept when within rel_tol * delta.
// Error of a pair: E = (Q_i^-1 Q_j)^-1 (P_i^-1 P_j), Q ground truth, P estimate; translation |t(E)|,
// rotation angle(E).
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "tools/eval/alignment.hpp"
#include "tools/eval/association.hpp"
#include "tools/eval/error_statistics.hpp"

namespace heslam::eval {

enum class DeltaUnit { frames, meters };
std::optional<DeltaUnit> parse_delta_unit(std::string_view name);  // "frames"/"f", "m"/"meters"
const char* delta_unit_name(DeltaUnit unit);

struct RpeOptions {
  double delta = 1.0;  // frames (integer) or metres
  DeltaUnit unit = DeltaUnit::frames;
  bool all_pairs = false;
  double rel_tol = 0.1;               // --all-pairs in metres: accepted |path - delta| / delta (evo)
  AlignMode align = AlignMode::none;  // RPE is alignment-free except for the scale (sim3)
};

struct RpeResult {
  RpeOptions options;
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  std::vector<double> translation_errors_m;
  std::vector<double> rotation_errors_deg;
  ErrorStats translation_m;
  ErrorStats rotation_deg;
};

// The pairs of rows of `poses` (see above); exposed for tests.
std::vector<std::pair<std::size_t, std::size_t>> rpe_pairs(const Trajectory& est, const RpeOptions& options);

// Throws std::runtime_error when the options are invalid or no pair fits in the trajectory.
RpeResult compute_rpe(const AlignedPair& pair, const RpeOptions& options);

}  // namespace heslam::eval

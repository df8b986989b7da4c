// Absolute pose error (ATE): per paired pose, after aligning the estimate to the ground truth.
//
// API:
//   AlignedPair pair = associate(gt, est);
//   ApeResult ape = compute_ape(pair, ApeOptions{.align = AlignMode::se3});
//   ape.translation_m.rmse      // the ATE figure papers quote
//   ape.rotation_deg            // angle of T_gt^-1 * T_est_aligned per pair
//   compute_ape(gt, est, ApeOptions{}, AssociationOptions{})   // associates first (one call)
// Translation error = |t_gt - t_est_aligned| (evo's APE translation_part).
#pragma once

#include <vector>

#include "tools/eval/alignment.hpp"
#include "tools/eval/association.hpp"
#include "tools/eval/error_statistics.hpp"

namespace heslam::eval {

struct ApeOptions {
  // SE(3) suits metric (stereo, RGB-D) estimates; sim3 for monocular ones.
  AlignMode align = AlignMode::se3;
};

struct ApeResult {
  AlignMode align = AlignMode::se3;
  Sim3 alignment;          // applied to the estimate
  Trajectory est_aligned;  // the estimate after alignment, paired row by row with `gt`
  Trajectory gt;
  std::vector<double> translation_errors_m;
  std::vector<double> rotation_errors_deg;
  ErrorStats translation_m;
  ErrorStats rotation_deg;
};

ApeResult compute_ape(const AlignedPair& pair, const ApeOptions& options = {});
ApeResult compute_ape(const Trajectory& gt, const Trajectory& est, const ApeOptions& options = {},
                      const AssociationOptions& association = {});

}  // namespace heslam::eval

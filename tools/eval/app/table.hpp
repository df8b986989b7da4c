// The plain-text result tables heslam-eval prints on stdout, and the per-pair error tables of
// --errors FILE (one row per pair, '#' header; for plotting or picking out a stretch of a run).
#pragma once

#include <iosfwd>
#include <string>

#include "tools/eval/ape.hpp"
#include "tools/eval/kitti_metrics.hpp"
#include "tools/eval/rpe.hpp"

namespace heslam::eval::app {

// readable: a unit that fits the errors (mm when every translation error is below 1 m, else m), 3
// decimals; full: 12-17 significant digits in m and deg, to compare with evo / kitti-odom-eval.
enum class Precision { readable, full };

void print_ape(std::ostream& out, const ApeResult& ape, Precision precision = Precision::readable);
void print_rpe(std::ostream& out, const RpeResult& rpe, Precision precision = Precision::readable);
void print_kitti(std::ostream& out, const KittiResult& kitti, Precision precision = Precision::readable);

// APE: estimate row, stamp (s, or the frame id without stamps), translation error (m) and its x y z
// in the ground truth's frame (aligned estimate - ground truth), rotation error (deg), and the
// ground truth's path length (m) from its first pose to the pair's (`gt`: the whole ground truth the
// pair was associated from; an interpolated pair counts to the ground-truth pose before its stamp).
std::string ape_error_rows(const ApeResult& ape, const AlignedPair& pair, const Trajectory& gt);
// RPE: the two estimate rows of each pair, their stamps (or frame ids), translation (m) and rotation
// (deg) errors.
std::string rpe_error_rows(const RpeResult& rpe, const AlignedPair& pair);

}  // namespace heslam::eval::app

// The plain-text result tables heslam-eval prints on stdout.
#pragma once

#include <iosfwd>

#include "tools/eval/ape.hpp"
#include "tools/eval/kitti_metrics.hpp"
#include "tools/eval/rpe.hpp"

namespace heslam::eval::app {

void print_ape(std::ostream& out, const ApeResult& ape);
void print_rpe(std::ostream& out, const RpeResult& rpe);
void print_kitti(std::ostream& out, const KittiResult& kitti);

}  // namespace heslam::eval::app

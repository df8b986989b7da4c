// Evaluation plots: top view of the aligned estimate over the ground truth, and the error over time.
//
// API:
//   write_plot("ape.png", ape_plot(ape_result, "KITTI 00, ORB-SLAM2"));   // or .svg
//   write_plot("rpe.svg", rpe_plot(pair, rpe_result, "..."));
//   write_plot("09.png", kitti_plot(kitti_result, "..."));   // error = position error per frame
// The top view shows the two axes along which the ground truth extends most (x-z for KITTI camera
// frames, x-y for TUM / EuRoC worlds) at equal scale, in metres.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "tools/eval/ape.hpp"
#include "tools/eval/kitti_metrics.hpp"
#include "tools/eval/rpe.hpp"
#include "tools/eval/trajectory.hpp"

namespace heslam::eval {

struct PlotInput {
  std::string title;
  Trajectory gt;
  Trajectory est;               // already aligned to gt
  std::vector<double> error_x;  // x of each error: seconds since the first pose, or a row index
  std::string error_x_label = "time [s]";
  std::vector<double> errors;
  std::string error_label = "APE translation [m]";
  double rmse = 0.0;
};

PlotInput ape_plot(const ApeResult& ape, const std::string& title);
PlotInput rpe_plot(const AlignedPair& pair, const RpeResult& rpe, const std::string& title);
PlotInput kitti_plot(const KittiResult& kitti, const std::string& title);

// PNG or SVG by extension; throws std::runtime_error naming the file on failure.
void write_plot(const std::filesystem::path& path, const PlotInput& input);

}  // namespace heslam::eval

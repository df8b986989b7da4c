// Command line of heslam-eval: the command and its options, parsed with one-line errors.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "tools/eval/alignment.hpp"
#include "tools/eval/rpe.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::eval::app {

enum class Command { ape, rpe, kitti };

inline const std::filesystem::path kStdout = "-";

struct CliOptions {
  Command command = Command::ape;
  std::filesystem::path gt_path;
  std::filesystem::path est_path;
  ReadOptions gt_read;
  ReadOptions est_read;
  // Unset: the command's default (ape se3, rpe none, kitti none).
  std::optional<AlignMode> align;
  double max_dt_s = 0.01;
  double est_offset_s = 0.0;
  bool interpolate_gt = false;
  RpeOptions rpe;
  // kStdout ("-"): JSON on stdout instead of the tables.
  std::filesystem::path json_path;
  bool full_precision = false;
  std::filesystem::path plot_path;
  std::filesystem::path errors_path;
  bool help = false;
};

// Throws std::runtime_error with a one-line message on bad arguments.
CliOptions parse_cli(int argc, char** argv);

std::string usage();

}  // namespace heslam::eval::app

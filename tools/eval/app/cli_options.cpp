// Parsing heslam-eval's arguments.
#include "tools/eval/app/cli_options.hpp"

#include <charconv>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <vector>

namespace heslam::eval::app {

namespace {

double parse_number(std::string_view flag, std::string_view text) {
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size()) {
    throw std::runtime_error(std::string(flag) + ": expected a number, got '" + std::string(text) + "'");
  }
  return value;
}

Format parse_format_flag(std::string_view flag, std::string_view text) {
  const auto format = parse_format(text);
  if (!format) throw std::runtime_error(std::string(flag) + ": expected tum, kitti, euroc or heslam, got '" + std::string(text) + "'");
  return *format;
}

}  // namespace

const char* usage() {
  return "usage: heslam-eval <ape|rpe|kitti> --gt FILE --est FILE [options]\n"
         "  ape    absolute trajectory error after alignment (default --align se3)\n"
         "  rpe    relative pose error over --delta N --unit frames|m [--all-pairs] (default --align none)\n"
         "  kitti  KITTI devkit drift over 100..800 m, plus ATE and RPE (default --align none)\n"
         "options:\n"
         "  --gt-format, --est-format F   tum | kitti | euroc | heslam (= tum); default: detected\n"
         "  --times FILE                  times.txt for KITTI pose files (both sides)\n"
         "  --gt-times, --est-times FILE  times.txt for one side only\n"
         "  --extrinsic sensor.yaml       EuRoC T_BS: ground truth body poses -> camera poses\n"
         "  --est-extrinsic sensor.yaml   the same for an estimate in EuRoC body poses\n"
         "  --align none|origin|se3|sim3  alignment of the estimate to the ground truth\n"
         "  --max-dt S                    largest stamp difference when associating by time (0.01)\n"
         "  --offset S                    added to the estimate's stamps before associating (0)\n"
         "  --interpolate-gt              pair each estimate pose with the ground truth interpolated at its\n"
         "                                stamp (+ offset): linear position, slerp rotation\n"
         "  --delta N  --unit frames|m  --all-pairs   RPE pairs (delta 1, frames)\n"
         "  --json [FILE]                 the results as JSON: into FILE, or alone (or '-') instead of the\n"
         "                                tables on stdout, for scripts\n"
         "  --full-precision              tables in m and deg with 12-17 significant digits (to compare\n"
         "                                with evo / kitti-odom-eval); default: mm below 1 m, 3 decimals\n"
         "  --plot FILE.png|FILE.svg      top view of the aligned trajectories and the error over time\n"
         "  --errors FILE                 ape / rpe: one row per pair (stamps, errors; ape also the error\n"
         "                                vector), to plot or to look at a stretch of the run\n";
}

CliOptions parse_cli(int argc, char** argv) {
  CliOptions options;
  const std::vector<std::string_view> args(argv + 1, argv + argc);
  if (args.empty()) throw std::runtime_error("missing command (ape, rpe or kitti); see --help");
  std::size_t i = 0;
  if (args[0] == "-h" || args[0] == "--help") {
    options.help = true;
    return options;
  }
  if (args[0] == "ape") options.command = Command::ape;
  else if (args[0] == "rpe") options.command = Command::rpe;
  else if (args[0] == "kitti") options.command = Command::kitti;
  else throw std::runtime_error("unknown command '" + std::string(args[0]) + "' (expected ape, rpe or kitti)");
  ++i;

  std::filesystem::path times_both;
  for (; i < args.size(); ++i) {
    const std::string_view flag = args[i];
    if (flag == "-h" || flag == "--help") {
      options.help = true;
      return options;
    }
    if (flag == "--all-pairs") {
      options.rpe.all_pairs = true;
      continue;
    }
    if (flag == "--interpolate-gt") {
      options.interpolate_gt = true;
      continue;
    }
    if (flag == "--full-precision") {
      options.full_precision = true;
      continue;
    }
    // --json alone (last, or before another option) or "--json -": the JSON document on stdout.
    if (flag == "--json" && (i + 1 >= args.size() || args[i + 1] == "-" || args[i + 1].starts_with("--"))) {
      options.json_path = kStdout;
      if (i + 1 < args.size() && args[i + 1] == "-") ++i;
      continue;
    }
    if (i + 1 >= args.size()) throw std::runtime_error(std::string(flag) + ": missing value");
    const std::string_view value = args[++i];
    if (flag == "--gt") options.gt_path = value;
    else if (flag == "--est") options.est_path = value;
    else if (flag == "--gt-format") options.gt_read.format = parse_format_flag(flag, value);
    else if (flag == "--est-format") options.est_read.format = parse_format_flag(flag, value);
    else if (flag == "--times") times_both = value;
    else if (flag == "--gt-times") options.gt_read.times_path = value;
    else if (flag == "--est-times") options.est_read.times_path = value;
    else if (flag == "--extrinsic") options.gt_read.extrinsic_path = value;
    else if (flag == "--est-extrinsic") options.est_read.extrinsic_path = value;
    else if (flag == "--align") {
      options.align = parse_align_mode(value);
      if (!options.align) throw std::runtime_error("--align: expected none, origin, se3 or sim3, got '" + std::string(value) + "'");
    } else if (flag == "--max-dt") {
      options.max_dt_s = parse_number(flag, value);
      if (!(options.max_dt_s >= 0.0)) throw std::runtime_error("--max-dt: expected a non-negative number of seconds");
    } else if (flag == "--offset") options.est_offset_s = parse_number(flag, value);
    else if (flag == "--delta") options.rpe.delta = parse_number(flag, value);
    else if (flag == "--unit") {
      const auto unit = parse_delta_unit(value);
      if (!unit) throw std::runtime_error("--unit: expected frames or m, got '" + std::string(value) + "'");
      options.rpe.unit = *unit;
    } else if (flag == "--json") options.json_path = value;
    else if (flag == "--plot") options.plot_path = value;
    else if (flag == "--errors") options.errors_path = value;
    else throw std::runtime_error("unknown option '" + std::string(flag) + "'; see --help");
  }
  if (options.gt_path.empty()) throw std::runtime_error("missing --gt FILE");
  if (options.est_path.empty()) throw std::runtime_error("missing --est FILE");
  if (!options.errors_path.empty() && options.command == Command::kitti) {
    throw std::runtime_error("--errors: only for ape and rpe (kitti reports per-length segments)");
  }
  // --times belongs to whichever side is a KITTI pose file.
  if (!times_both.empty()) {
    for (auto [path, read] : {std::pair{&options.gt_path, &options.gt_read}, std::pair{&options.est_path, &options.est_read}}) {
      const Format format = read->format ? *read->format : detect_format(*path);
      if (format == Format::kitti && read->times_path.empty()) read->times_path = times_both;
    }
  }
  return options;
}

}  // namespace heslam::eval::app

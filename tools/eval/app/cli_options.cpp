// Parsing heslam-eval's arguments.
#include "tools/eval/app/cli_options.hpp"

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "runtime/flags.hpp"
#include "runtime/quote_value.hpp"

namespace heslam::eval::app {

namespace {

// The command line, declared once for the parser and the usage. times_both: --times, resolved
// after parsing (it belongs to whichever side is a KITTI pose file).
runtime::Flags eval_flags(CliOptions& options, std::filesystem::path& times_both, bool& command_given) {
  runtime::Flags flags(
      "heslam-eval <ape|rpe|kitti> --gt FILE --est FILE [options]",
      "  ape    absolute trajectory error after alignment (default --align se3)\n"
      "  rpe    relative pose error over --delta N --unit frames|m [--all-pairs] (default --align none)\n"
      "  kitti  KITTI devkit drift over 100..800 m, plus ATE and RPE (default --align none)\n"
      "options:");
  const auto format = [](std::optional<Format>& target, std::string flag) {
    return [&target, flag](const std::string& value) {
      target = parse_format(value);
      if (!target) runtime::throw_bad_flag_value(flag, "tum, kitti, euroc or heslam", value);
    };
  };
  flags.path("--gt", "FILE", &options.gt_path, "the ground truth")
      .path("--est", "FILE", &options.est_path, "the estimate")
      .custom("--gt-format", "F", "tum | kitti | euroc | heslam (= tum); default: detected",
              format(options.gt_read.format, "--gt-format"))
      .custom("--est-format", "F", "the same for the estimate", format(options.est_read.format, "--est-format"))
      .path("--times", "FILE", &times_both, "times.txt for KITTI pose files (both sides)")
      .path("--gt-times", "FILE", &options.gt_read.times_path, "times.txt for the ground truth only")
      .path("--est-times", "FILE", &options.est_read.times_path, "times.txt for the estimate only")
      .path("--extrinsic", "sensor.yaml", &options.gt_read.extrinsic_path,
            "EuRoC T_BS: ground truth body poses -> camera poses")
      .path("--est-extrinsic", "sensor.yaml", &options.est_read.extrinsic_path,
            "the same for an estimate in EuRoC body poses")
      .custom("--align", "none|origin|se3|sim3", "alignment of the estimate to the ground truth",
              [&options](const std::string& value) {
                options.align = parse_align_mode(value);
                if (!options.align) runtime::throw_bad_flag_value("--align", "none, origin, se3 or sim3", value);
              })
      .number("--max-dt", "S", &options.max_dt_s, 0.0, std::numeric_limits<double>::infinity(),
              "largest stamp difference when associating by time (0.01)")
      .number("--offset", "S", &options.est_offset_s, "added to the estimate's stamps before associating (0)")
      .toggle("--interpolate-gt", &options.interpolate_gt,
              "pair each estimate pose with the ground truth interpolated at its\n"
              "stamp (+ offset): linear position, slerp rotation")
      .number("--delta", "N", &options.rpe.delta, "RPE pairs: frames or metres apart (1)")
      .custom("--unit", "frames|m", "RPE: the unit of --delta (frames)",
              [&options](const std::string& value) {
                const auto unit = parse_delta_unit(value);
                if (!unit) runtime::throw_bad_flag_value("--unit", "frames or m", value);
                options.rpe.unit = *unit;
              })
      .toggle("--all-pairs", &options.rpe.all_pairs, "RPE: every pair --delta apart, not consecutive ones")
      .path("--json", "[FILE]", &options.json_path,
            "the results as JSON: into FILE, or alone (or '-') instead of the\n"
            "tables on stdout, for scripts")
      .toggle("--full-precision", &options.full_precision,
              "tables in m and deg with 12-17 significant digits (to compare\n"
              "with evo / kitti-odom-eval); default: mm below 1 m, 3 decimals")
      .path("--plot", "FILE.png|FILE.svg", &options.plot_path,
            "top view of the aligned trajectories and the error over time")
      .path("--errors", "FILE", &options.errors_path,
            "ape / rpe: one row per pair (stamps, errors; ape also the error\n"
            "vector), to plot or to look at a stretch of the run")
      .toggle("--help", &options.help, "this help")
      .alias("-h")
      .positional("COMMAND", "", [&options, &command_given](const std::string& arg) {
        if (command_given)
          throw std::runtime_error("unexpected argument '" + runtime::quote_value(arg) + "'; see --help");
        if (arg == "ape")
          options.command = Command::ape;
        else if (arg == "rpe")
          options.command = Command::rpe;
        else if (arg == "kitti")
          options.command = Command::kitti;
        else
          throw std::runtime_error("unknown command '" + runtime::quote_value(arg) + "' (expected ape, rpe or kitti)");
        command_given = true;
      });
  return flags;
}

}  // namespace

std::string usage() {
  CliOptions unused;
  std::filesystem::path unused_times;
  bool unused_command = false;
  return eval_flags(unused, unused_times, unused_command).usage();
}

CliOptions parse_cli(int argc, char** argv) {
  CliOptions options;
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) throw std::runtime_error("missing command (ape, rpe or kitti); see --help");
  // --json alone (last, or before another option): the JSON document on stdout, as "--json -".
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--json" && (i + 1 >= args.size() || args[i + 1].starts_with("--"))) args[i] = "--json=-";
  }
  std::filesystem::path times_both;
  bool command_given = false;
  eval_flags(options, times_both, command_given).parse(args);
  if (options.help) return options;
  if (!command_given) throw std::runtime_error("missing command (ape, rpe or kitti); see --help");
  if (options.gt_path.empty()) throw std::runtime_error("missing --gt FILE");
  if (options.est_path.empty()) throw std::runtime_error("missing --est FILE");
  if (!options.errors_path.empty() && options.command == Command::kitti) {
    throw std::runtime_error("--errors: only for ape and rpe (kitti reports per-length segments)");
  }
  // --times belongs to whichever side is a KITTI pose file.
  if (!times_both.empty()) {
    for (auto [path, read] :
         {std::pair{&options.gt_path, &options.gt_read}, std::pair{&options.est_path, &options.est_read}}) {
      const Format format = read->format ? *read->format : detect_format(*path);
      if (format == Format::kitti && read->times_path.empty()) read->times_path = times_both;
    }
  }
  return options;
}

}  // namespace heslam::eval::app
